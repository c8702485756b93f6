/* EasyLab host board: the Modbus links of the service interface
 * (runtime_c/el_modbus_port.h, docs/service.md).
 *
 *   --modbus-tcp PORT      serve the model's `modbus tcp` interface on
 *                          127.0.0.1:PORT (default: the model's port),
 *                          EL_HOST_MB_TCP_CONNS clients at once (a new
 *                          client replaces the least recently active one);
 *                          a client that does not read its replies is
 *                          dropped, never waited for
 *   --modbus-rtu pty:LINK  serve its `modbus rtu` interface on a new
 *                          pseudo-terminal; LINK is a symlink to it
 *                          (replaced if it is a stale symlink, removed at
 *                          exit); any serial tool opens LINK (8N1: this
 *                          kernel's ptys refuse even parity)
 *
 * Both may be given; each serves only if the model declares that
 * interface. The descriptors are opened when the option is read (so a busy
 * port or a bad link is a command-line error, exit status 2) and served
 * between instants (el_host_watch_fd): the handlers here only move bytes
 * into buffers; the runtime's slave takes them from el_idle, right after,
 * through el_port_mb_* (pull: the board never calls into the runtime).
 *
 * RTU framing on a pty: there is no character timing, so frames end (a) at
 * a silence of 3.5 characters at the model's baud rate, at least
 * EL_HOST_MB_SILENCE_MIN_US, measured on CLOCK_MONOTONIC between bursts of
 * bytes (and noticed when the next burst comes or at the next idle call),
 * and (b) as soon as the bytes form a CRC-valid request of the length its
 * function code implies (EL_MB_PORT_UNTIMED: the runtime's `early` mode).
 * Garbage followed by a silence is dropped with it; garbage glued to a
 * request without a silence spoils that request, as it would on a line.
 * Replies are never waited for: when the pty is full of replies nobody
 * reads, those are discarded (el_port_mb_rtu_send).
 *
 * Local execution replaces a model's interfaces library while it runs
 * (host_interp.c): el_host_modbus_handover passes the listening socket,
 * the TCP clients and the RTU pty to the next library in the environment
 * variable EL_HOST_MODBUS_FDS, which adopts them instead of opening its
 * own, so clients stay connected. A reset (exec) closes them instead.
 */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif
#ifndef _XOPEN_SOURCE
#define _XOPEN_SOURCE 700 /* posix_openpt, grantpt, unlockpt, ptsname */
#endif

#include "host_internal.h"
#include "el_modbus_port.h"
#include "el_service.h"

#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

/* TCP clients served at once. When every slot is taken, a new client
 * takes the slot of the least recently active one (the one whose last
 * request is the oldest), so a new client is always served and idle
 * clients never lock the others out. */
#define EL_HOST_MB_TCP_CONNS 10u
/* Request bytes buffered per TCP client (at least one whole ADU, 260). */
#define EL_HOST_MB_TCP_BUF 1024u
/* Reply bytes kept per TCP client once its socket takes no more (the
 * client does not read): written when the socket has room again, never
 * waited for; a reply that does not fit drops the client. */
#define EL_HOST_MB_TCP_OUT 2048u
/* Receive events buffered on the RTU pty (bytes and silence marks). */
#define EL_HOST_MB_RTU_RING 1024u
/* The shortest silence that ends an RTU frame on a pty, in microseconds
 * (scheduling jitter on a host is larger than t3.5). */
#define EL_HOST_MB_SILENCE_MIN_US 5000u

/* ---- helpers ---- */

static bool set_flags(int fd)
{
    int fl = fcntl(fd, F_GETFL), fd_fl = fcntl(fd, F_GETFD);
    /* Non-blocking; closed on exec (the debugger's reset executes the
     * program again, which opens its own links). */
    return fl >= 0 && fd_fl >= 0 && fcntl(fd, F_SETFL, fl | O_NONBLOCK) == 0 &&
           fcntl(fd, F_SETFD, fd_fl | FD_CLOEXEC) == 0;
}

static uint64_t now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000000u + (uint64_t)ts.tv_nsec;
}

/* Write `data` to a non-blocking descriptor as far as it takes it now,
 * never waiting: whether all of it went. */
static bool write_now(int fd, const uint8_t *data, size_t len)
{
    while (len > 0u) {
        ssize_t n = write(fd, data, len);
        if (n > 0) {
            data += n;
            len -= (size_t)n;
        } else if (n == 0 || errno != EINTR) {
            return false;
        }
    }
    return true;
}

/* Links made by this file, removed at exit. */
static char link_paths[2][4096];
static bool atexit_done;

static void remove_links(void)
{
    size_t i;
    for (i = 0; i < 2u; i++)
        if (link_paths[i][0] != '\0') {
            struct stat st;
            if (lstat(link_paths[i], &st) == 0 && S_ISLNK(st.st_mode))
                (void)unlink(link_paths[i]);
            link_paths[i][0] = '\0';
        }
}

/* A pty whose slave LINK points at: returns the master (and our own slave
 * descriptor, kept open so that the master never sees a hangup between
 * clients), or -1 after reporting. Shared with host_hmi.c. */
int el_host_make_pty(const char *option, const char *link, int *slave_out)
{
    struct termios tio;
    struct stat st;
    const char *name;
    int master, slave;
    size_t slot;

    if (link[0] == '\0') {
        el_host_error("%s pty:LINK: give the path of the link", option);
        return -1;
    }
    if (strlen(link) >= sizeof link_paths[0]) {
        el_host_error("%s: link path too long", option);
        return -1;
    }
    if (lstat(link, &st) == 0 && !S_ISLNK(st.st_mode)) {
        el_host_error("%s pty:%s: the path exists and is not a symlink", option, link);
        return -1;
    }
    master = posix_openpt(O_RDWR | O_NOCTTY);
    if (master < 0 || grantpt(master) != 0 || unlockpt(master) != 0 || (name = ptsname(master)) == NULL) {
        el_host_error("%s: cannot make a pseudo-terminal: %s", option, strerror(errno));
        if (master >= 0)
            close(master);
        return -1;
    }
    slave = open(name, O_RDWR | O_NOCTTY);
    if (slave < 0) {
        el_host_error("%s: cannot open %s: %s", option, name, strerror(errno));
        close(master);
        return -1;
    }
    /* Raw 8N1, no echo: the bytes pass as they are. */
    if (tcgetattr(slave, &tio) == 0) {
        tio.c_iflag &= ~(tcflag_t)(IGNBRK | BRKINT | PARMRK | ISTRIP | INLCR | IGNCR | ICRNL | IXON | IXOFF);
        tio.c_oflag &= ~(tcflag_t)OPOST;
        tio.c_lflag &= ~(tcflag_t)(ECHO | ECHONL | ICANON | ISIG | IEXTEN);
        tio.c_cflag &= ~(tcflag_t)(CSIZE | PARENB | CSTOPB);
        tio.c_cflag |= CS8 | CREAD | CLOCAL;
        tio.c_cc[VMIN] = 1;
        tio.c_cc[VTIME] = 0;
        (void)tcsetattr(slave, TCSANOW, &tio);
    }
    if (!set_flags(master) || !set_flags(slave)) {
        el_host_error("%s: cannot set up the pseudo-terminal: %s", option, strerror(errno));
        close(master);
        close(slave);
        return -1;
    }
    (void)unlink(link); /* a stale symlink of an earlier run */
    if (symlink(name, link) != 0) {
        el_host_error("%s pty:%s: cannot make the link: %s", option, link, strerror(errno));
        close(master);
        close(slave);
        return -1;
    }
    slot = link_paths[0][0] == '\0' ? 0u : 1u;
    if (link_paths[slot][0] == '\0')
        strcpy(link_paths[slot], link);
    if (!atexit_done) {
        atexit_done = true;
        (void)atexit(remove_links);
    }
    *slave_out = slave;
    return master;
}

/* ---- descriptors handed over by a replaced interfaces library ---- */

#define MB_FDS_ENV "EL_HOST_MODBUS_FDS"

/* What EL_HOST_MODBUS_FDS holds: "LISTEN RTU KEEP CONN..." (-1: none),
 * read once; each is taken by the option that opens its kind. */
static bool handed_read;
static int handed_listen = -1, handed_rtu = -1, handed_keep = -1;
static int handed_conns[EL_HOST_MB_TCP_CONNS];
static size_t handed_conn_count;

static bool open_fd(int fd)
{
    return fd >= 0 && fcntl(fd, F_GETFD) >= 0;
}

static void read_handed(void)
{
    const char *text = getenv(MB_FDS_ENV);
    char *end;
    long v[3 + EL_HOST_MB_TCP_CONNS];
    size_t n = 0;
    if (handed_read)
        return;
    handed_read = true;
    if (text == NULL)
        return;
    while (n < sizeof v / sizeof v[0]) {
        v[n] = strtol(text, &end, 10);
        if (end == text)
            break;
        n++;
        text = end;
    }
    (void)unsetenv(MB_FDS_ENV);
    if (n < 3u)
        return;
    handed_listen = open_fd((int)v[0]) ? (int)v[0] : -1;
    handed_rtu = open_fd((int)v[1]) ? (int)v[1] : -1;
    handed_keep = open_fd((int)v[2]) ? (int)v[2] : -1;
    for (; n > 3u && handed_conn_count < EL_HOST_MB_TCP_CONNS; n--)
        if (open_fd((int)v[n - 1u]))
            handed_conns[handed_conn_count++] = (int)v[n - 1u];
}

/* ---- RTU on a pty ---- */

static int rtu_fd = -1, rtu_keep = -1;
static uint16_t rtu_ring[EL_HOST_MB_RTU_RING]; /* bytes 0..255, or RING_SILENCE */
static size_t rtu_head, rtu_count;
static uint64_t rtu_last_ns;   /* when the last burst of bytes came */
static bool rtu_since_silence; /* bytes came since the last silence mark */
static uint64_t rtu_silence_ns = (uint64_t)EL_HOST_MB_SILENCE_MIN_US * 1000u;
#define RING_SILENCE 0x100u

static void ring_put(uint16_t v)
{
    if (rtu_count < EL_HOST_MB_RTU_RING) {
        rtu_ring[(rtu_head + rtu_count) % EL_HOST_MB_RTU_RING] = v;
        rtu_count++;
    }
}

static void rtu_readable(int fd, short revents, void *ctx)
{
    uint8_t buf[512];
    size_t room = EL_HOST_MB_RTU_RING - rtu_count;
    ssize_t n, i;
    uint64_t now;
    (void)ctx;
    (void)revents;
    if (room < 2u)
        return; /* the slave takes events right after this (el_idle) */
    n = read(fd, buf, room - 1u < sizeof buf ? room - 1u : sizeof buf);
    if (n <= 0)
        return;
    now = now_ns();
    if (rtu_since_silence && now - rtu_last_ns >= rtu_silence_ns) {
        ring_put(RING_SILENCE);
        rtu_since_silence = false;
    }
    for (i = 0; i < n; i++)
        ring_put(buf[i]);
    rtu_last_ns = now;
    rtu_since_silence = true;
}

bool el_host_opt_modbus_rtu(const char *arg)
{
    if (strncmp(arg, "pty:", 4) != 0) {
        el_host_error("--modbus-rtu %s: give pty:LINK (a pseudo-terminal with a symlink LINK to it)", arg);
        return false;
    }
    if ((el_svc_modbus_links & EL_SVC_LINK_RTU) == 0u) {
        el_host_error("--modbus-rtu: model %s has no Modbus RTU interface (declare one: `modbus rtu on uart0`)",
                      el_model_name);
        return false;
    }
    read_handed();
    if (handed_rtu >= 0 && strlen(arg + 4) < sizeof link_paths[0]) { /* the pty of the replaced library */
        rtu_fd = handed_rtu;
        rtu_keep = handed_keep;
        handed_rtu = handed_keep = -1;
        strcpy(link_paths[link_paths[0][0] == '\0' ? 0u : 1u], arg + 4);
        if (!atexit_done) {
            atexit_done = true;
            (void)atexit(remove_links);
        }
    } else {
        rtu_fd = el_host_make_pty("--modbus-rtu", arg + 4, &rtu_keep);
    }
    if (rtu_fd < 0)
        return false;
    if (!el_host_watch_fd(rtu_fd, rtu_readable, NULL))
        return false;
    return true;
}

uint8_t el_port_mb_rtu_open(uint8_t uart, uint32_t baud, uint8_t parity, uint8_t unit)
{
    uint64_t t35_ns;
    (void)uart;
    (void)parity; /* a pty has no parity: the client chooses 8N1 */
    (void)unit;
    if (rtu_fd < 0)
        return EL_MB_PORT_OFF;
    /* 3.5 characters of 11 bits; 1.75 ms above 19200 baud. */
    t35_ns = baud > 19200u || baud == 0u ? 1750000u : (uint64_t)38500000000u / baud;
    rtu_silence_ns = t35_ns > (uint64_t)EL_HOST_MB_SILENCE_MIN_US * 1000u ? t35_ns
                                                                         : (uint64_t)EL_HOST_MB_SILENCE_MIN_US * 1000u;
    return EL_MB_PORT_UNTIMED;
}

int16_t el_port_mb_rtu_getc(void)
{
    uint16_t v;
    if (rtu_count == 0u) {
        if (rtu_since_silence && now_ns() - rtu_last_ns >= rtu_silence_ns) {
            rtu_since_silence = false;
            return EL_MB_SILENCE;
        }
        return EL_MB_NONE;
    }
    v = rtu_ring[rtu_head];
    rtu_head = (rtu_head + 1u) % EL_HOST_MB_RTU_RING;
    rtu_count--;
    return v == RING_SILENCE ? EL_MB_SILENCE : (int16_t)v;
}

void el_port_mb_rtu_send(const uint8_t *adu, uint16_t len)
{
    if (rtu_fd < 0 || write_now(rtu_fd, adu, len))
        return;
    /* The pty is full of replies nobody reads (a client that does not
     * read, or that left): they are dropped, with whatever part of this
     * one went, and this one is written whole. Never waited for; if the
     * pty still has no room, the reply is lost, as on a line. */
    if (rtu_keep >= 0 && tcflush(rtu_keep, TCIFLUSH) == 0)
        (void)write_now(rtu_fd, adu, len);
}

/* ---- TCP ---- */

/* A client's slot. Nothing here ever waits for a client: requests are
 * read as they come, replies go out as far as the socket takes them and
 * the rest waits in `out` until poll() says the socket has room
 * (el_host_out_put, host_serve.c). */
typedef struct {
    int fd;             /* -1: free */
    size_t len;         /* request bytes in buf */
    el_host_out_t out;  /* replies waiting, in out_buf */
    uint64_t active_ns; /* when the client last sent bytes, or connected */
    uint8_t buf[EL_HOST_MB_TCP_BUF];
    uint8_t out_buf[EL_HOST_MB_TCP_OUT];
} tcp_conn_t;

static int tcp_listen = -1;
static uint16_t tcp_port_option; /* --modbus-tcp, 0: none */
static tcp_conn_t tcp_conns[EL_HOST_MB_TCP_CONNS];
static bool tcp_init_done;
static bool tcp_served; /* the model has a `modbus tcp` interface (el_port_mb_tcp_open came) */

static void tcp_init(void)
{
    size_t i;
    if (tcp_init_done)
        return;
    tcp_init_done = true;
    for (i = 0; i < EL_HOST_MB_TCP_CONNS; i++)
        tcp_conns[i].fd = -1;
}

void el_port_mb_tcp_close(uint8_t conn)
{
    if (conn >= EL_HOST_MB_TCP_CONNS || tcp_conns[conn].fd < 0)
        return;
    el_host_unwatch_fd(tcp_conns[conn].fd);
    close(tcp_conns[conn].fd);
    tcp_conns[conn].fd = -1;
    tcp_conns[conn].len = 0;
    tcp_conns[conn].out.fd = -1;
    tcp_conns[conn].out.len = 0u;
}

/* Slot i serves client fd from now on. */
static void tcp_take(size_t i, int fd)
{
    tcp_conns[i].fd = fd;
    tcp_conns[i].len = 0;
    tcp_conns[i].active_ns = now_ns();
    el_host_out_init(&tcp_conns[i].out, fd, true, tcp_conns[i].out_buf, (uint16_t)sizeof tcp_conns[i].out_buf);
}

static void conn_readable(int fd, short revents, void *ctx)
{
    tcp_conn_t *c = (tcp_conn_t *)ctx;
    ssize_t n;
    if (c->fd != fd)
        return;
    if ((revents & POLLOUT) != 0 && !el_host_out_flush(&c->out)) {
        el_port_mb_tcp_close((uint8_t)(c - tcp_conns));
        return;
    }
    if ((revents & (POLLIN | POLLHUP | POLLERR | POLLNVAL)) == 0)
        return;
    if (c->len >= sizeof c->buf)
        return; /* full of whole requests: the slave takes them right after this */
    n = read(fd, c->buf + c->len, sizeof c->buf - c->len);
    if (n > 0) {
        c->len += (size_t)n;
        c->active_ns = now_ns();
        return;
    }
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR))
        return;
    el_port_mb_tcp_close((uint8_t)(c - tcp_conns)); /* closed by the client, or an error */
}

/* The slot for a new client: a free one, else that of the least recently
 * active client, which is dropped (a new client is always served). */
static size_t slot_for_new_client(void)
{
    size_t i, oldest = 0u;
    for (i = 0; i < EL_HOST_MB_TCP_CONNS; i++) {
        if (tcp_conns[i].fd < 0)
            return i;
        if (tcp_conns[i].active_ns < tcp_conns[oldest].active_ns)
            oldest = i;
    }
    el_port_mb_tcp_close((uint8_t)oldest);
    return oldest;
}

static void accept_ready(int fd, short revents, void *ctx)
{
    size_t i;
    int c;
    (void)revents;
    (void)ctx;
    c = accept(fd, NULL, NULL); /* closed at once when the model has no Modbus TCP */
    if (c < 0)
        return;
    if (!tcp_served || !set_flags(c)) {
        close(c);
        return;
    }
    i = slot_for_new_client();
    if (!el_host_watch_fd(c, conn_readable, &tcp_conns[i])) {
        close(c);
        return;
    }
    tcp_take(i, c);
}

static bool tcp_listen_on(uint16_t port, const char *what)
{
    struct sockaddr_in addr;
    int one = 1;
    tcp_init();
    read_handed();
    if (handed_listen >= 0) { /* the socket and clients of the replaced library */
        size_t i;
        tcp_listen = handed_listen;
        handed_listen = -1;
        for (i = 0; i < handed_conn_count; i++) {
            tcp_take(i, handed_conns[i]);
            if (!el_host_watch_fd(tcp_conns[i].fd, conn_readable, &tcp_conns[i]))
                el_port_mb_tcp_close((uint8_t)i);
        }
        handed_conn_count = 0;
        return el_host_watch_fd(tcp_listen, accept_ready, NULL);
    }
    tcp_listen = socket(AF_INET, SOCK_STREAM, 0);
    if (tcp_listen < 0) {
        el_host_error("%s: cannot make a socket: %s", what, strerror(errno));
        return false;
    }
    (void)setsockopt(tcp_listen, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    memset(&addr, 0, sizeof addr);
    addr.sin_family = AF_INET;
    addr.sin_port = htons(port);
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (bind(tcp_listen, (struct sockaddr *)&addr, sizeof addr) != 0 || listen(tcp_listen, 16) != 0 ||
        !set_flags(tcp_listen)) {
        el_host_error("%s: cannot listen on 127.0.0.1:%u: %s", what, (unsigned)port, strerror(errno));
        close(tcp_listen);
        tcp_listen = -1;
        return false;
    }
    if (!el_host_watch_fd(tcp_listen, accept_ready, NULL)) {
        close(tcp_listen);
        tcp_listen = -1;
        return false;
    }
    return true;
}

bool el_host_opt_modbus_tcp(const char *arg)
{
    char *end;
    unsigned long port;
    errno = 0;
    port = strtoul(arg, &end, 10);
    if (arg[0] < '0' || arg[0] > '9' || *end != '\0' || errno != 0 || port < 1u || port > 65535u) {
        el_host_error("--modbus-tcp %s: give a TCP port, 1..65535", arg);
        return false;
    }
    if ((el_svc_modbus_links & EL_SVC_LINK_TCP) == 0u) {
        el_host_error("--modbus-tcp: model %s has no Modbus TCP interface (declare one: `modbus tcp port %lu`)",
                      el_model_name, port);
        return false;
    }
    tcp_port_option = (uint16_t)port;
    return tcp_listen_on(tcp_port_option, "--modbus-tcp");
}

uint8_t el_port_mb_tcp_open(uint16_t port)
{
    if (tcp_listen < 0 && !tcp_listen_on(port, "modbus tcp")) {
        /* The model's own port is taken: nothing can be served. */
        exit(EL_HOST_EXIT_USAGE);
    }
    tcp_served = true;
    return (uint8_t)EL_HOST_MB_TCP_CONNS;
}

uint16_t el_port_mb_tcp_peek(uint8_t conn, uint8_t *buf, uint16_t n)
{
    const tcp_conn_t *c;
    if (conn >= EL_HOST_MB_TCP_CONNS)
        return 0u;
    c = &tcp_conns[conn];
    if (c->fd < 0)
        return 0u;
    if (n > c->len)
        n = (uint16_t)c->len;
    memcpy(buf, c->buf, n);
    return n;
}

void el_port_mb_tcp_consume(uint8_t conn, uint16_t n)
{
    tcp_conn_t *c;
    if (conn >= EL_HOST_MB_TCP_CONNS)
        return;
    c = &tcp_conns[conn];
    if (n >= c->len) {
        c->len = 0;
        return;
    }
    memmove(c->buf, c->buf + n, c->len - n);
    c->len -= n;
}

bool el_port_mb_tcp_send(uint8_t conn, const uint8_t *adu, uint16_t len)
{
    if (conn >= EL_HOST_MB_TCP_CONNS || tcp_conns[conn].fd < 0)
        return false;
    if (el_host_out_put(&tcp_conns[conn].out, adu, len) != EL_HOST_OUT_SENT) {
        /* Broken, or a client that does not read its replies: dropped, never waited for. */
        el_port_mb_tcp_close(conn);
        return false;
    }
    return true;
}

/* ---- local execution: hand the links over to the next library ---- */

bool el_host_modbus_handover(void)
{
    char text[16 * (3u + EL_HOST_MB_TCP_CONNS)];
    size_t i, used;
    for (i = 0; i < EL_HOST_MB_TCP_CONNS; i++)
        if (tcp_conns[i].fd >= 0)
            (void)el_host_out_flush(&tcp_conns[i].out); /* what the socket takes now; the rest is lost with this library */
    used = (size_t)snprintf(text, sizeof text, "%d %d %d", tcp_listen, rtu_fd, rtu_keep);
    for (i = 0; i < EL_HOST_MB_TCP_CONNS; i++)
        if (tcp_conns[i].fd >= 0 && used < sizeof text)
            used += (size_t)snprintf(text + used, sizeof text - used, " %d", tcp_conns[i].fd);
    if (setenv(MB_FDS_ENV, text, 1) != 0) {
        el_host_error("Modbus links: cannot hand them over: %s", strerror(errno));
        return false;
    }
    link_paths[0][0] = link_paths[1][0] = '\0'; /* the next library keeps the links */
    return true;
}
