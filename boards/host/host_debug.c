/* EasyLab host board: the debug interface's transport (runtime_c/el_debug.h,
 * docs/protocol.md).
 *
 *   --debug pty:LINK[,halt]   make a pseudo-terminal and a symlink LINK to it
 *                             (removed at exit); any serial tool opens LINK
 *   --debug tcp:PORT[,halt]   listen on 127.0.0.1:PORT (0: any free port,
 *                             printed on stderr); one client at a time, a
 *                             new one replaces the old
 *   ,halt                     halt at the first instant, before anything
 *                             runs, until the debugger says run or step
 *
 * The descriptors are served between instants (el_host_watch_fd): while
 * waiting in real time, at every instant with --fast, and while the
 * program is halted. Responses are never waited for (el_host_out_put):
 * what the kernel does not take now waits in a buffer of
 * EL_HOST_DEBUG_OUT bytes, written when there is room. A debugger that
 * does not read its responses never stalls the program: on the pty, a
 * response that does not fit is dropped and counted by the server
 * (tx_dropped), said once on stderr until the debugger reads again; over
 * TCP, the client is dropped (said on stderr), and the next one is served.
 *
 * Reset (the protocol's RESET): the process executes itself again with the
 * same command line, handing over the open descriptors (environment
 * variable EL_HOST_DEBUG_FDS), so the debugger stays connected while the
 * program restarts from boot (traces start anew, --nvram keeps its data).
 *
 * Builds without the debug server (release builds, models without a debug
 * interface, the board's own test fixture) keep only the option, which
 * then says why there is no debug interface.
 */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif
#ifndef _XOPEN_SOURCE
#define _XOPEN_SOURCE 700 /* posix_openpt, grantpt, unlockpt, ptsname */
#endif

#include "host_internal.h"

#if defined(EL_DEBUG) && EL_DEBUG && !(defined(EL_RELEASE) && EL_RELEASE)
#include "el_debug.h"
#endif

#if defined(EL_DEBUG_SERVER) && EL_DEBUG_SERVER

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#define FDS_ENV "EL_HOST_DEBUG_FDS"
#define HALT_ENV "EL_HOST_DEBUG_HALT"

/* Response bytes waiting for the debugger to read (at least two of the
 * longest encoded response). */
#define EL_HOST_DEBUG_OUT 1024u
#if EL_HOST_DEBUG_OUT < 2u * (EL_DBG_MAX_FRAME + 8u)
#error "EL_HOST_DEBUG_OUT must hold two of the longest responses"
#endif

static enum { NONE, PTY, TCP } mode;
static int conn_fd = -1;    /* pty master, or the TCP client */
static el_host_out_t out;   /* responses waiting for room on conn_fd */
static uint8_t out_data[EL_HOST_DEBUG_OUT];
static bool dropping;       /* pty: responses are dropped (said once) until the debugger reads again */
static int keep_fd = -1;    /* pty: our own slave descriptor (no hangup between clients) */
static int listen_fd = -1;  /* TCP */
static char link_path[4096];
static bool link_made;
static struct sigaction chained[2]; /* SIGINT, SIGTERM as the board installed them */

static bool set_nonblocking(int fd)
{
    int flags = fcntl(fd, F_GETFL);
    return flags >= 0 && fcntl(fd, F_SETFL, flags | O_NONBLOCK) == 0;
}

static void on_signal(int sig)
{
    el_debug_abort_halt = 1u; /* a halted program must reach its next tick to stop */
    if (sig == SIGINT && chained[0].sa_handler != SIG_DFL && chained[0].sa_handler != SIG_IGN)
        chained[0].sa_handler(sig);
    else if (sig == SIGTERM && chained[1].sa_handler != SIG_DFL && chained[1].sa_handler != SIG_IGN)
        chained[1].sa_handler(sig);
}

static void chain_signals(void)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sigemptyset(&sa.sa_mask);
    sa.sa_handler = on_signal;
    if (sigaction(SIGINT, NULL, &chained[0]) == 0 && chained[0].sa_handler != SIG_IGN)
        (void)sigaction(SIGINT, &sa, NULL);
    if (sigaction(SIGTERM, NULL, &chained[1]) == 0 && chained[1].sa_handler != SIG_IGN)
        (void)sigaction(SIGTERM, &sa, NULL);
}

static void remove_link(void)
{
    char target[256];
    ssize_t n;
    const char *ours;
    el_host_drain_pty(keep_fd); /* let the debugger read what we answered last */
    if (link_made) {
        /* Only if it still leads to our pty (another run may have taken the name). */
        n = readlink(link_path, target, sizeof target - 1u);
        ours = conn_fd >= 0 ? ptsname(conn_fd) : NULL;
        if (n > 0 && ours != NULL) {
            target[n] = '\0';
            if (strcmp(target, ours) == 0)
                (void)unlink(link_path);
        }
        link_made = false;
    }
}

/* conn_fd (-1: none) is the debugger's link from now on. */
static void set_conn(int fd)
{
    conn_fd = fd;
    dropping = false;
    el_host_out_init(&out, fd, mode == TCP, out_data, (uint16_t)sizeof out_data);
}

/* pty: room again after responses were dropped. */
static void reads_again(void)
{
    if (dropping) {
        dropping = false;
        el_host_error("debug interface: the debugger reads its responses again");
    }
}

/* Close the TCP client. */
static void drop_client(void)
{
    el_host_unwatch_fd(conn_fd);
    (void)close(conn_fd);
    set_conn(-1);
}

static void on_conn(int fd, short revents, void *ctx)
{
    (void)ctx;
    if (fd != conn_fd)
        return;
    /* Room for the responses waiting. */
    if ((revents & POLLOUT) != 0) {
        if (!el_host_out_flush(&out) && mode == TCP) {
            drop_client();
            return;
        }
        if (out.len == 0u)
            reads_again();
    }
    /* Data are taken by el_debug_poll (from el_idle, right after this). A
     * TCP client that went away is closed; a pty never hangs up (we hold
     * its slave side open). */
    if (mode == TCP && (revents & (POLLHUP | POLLERR | POLLNVAL)) != 0 && (revents & POLLIN) == 0)
        drop_client();
}

static void on_listen(int fd, short revents, void *ctx)
{
    int client;
    (void)ctx;
    if ((revents & POLLIN) == 0 || (client = el_host_accept_tcp(fd)) < 0)
        return;
    if (conn_fd >= 0) /* a new client replaces the old one */
        drop_client();
    set_conn(client);
    if (!el_host_watch_fd(client, on_conn, NULL)) {
        (void)close(client);
        set_conn(-1);
    }
    el_debug_boot(); /* a fresh decoder for the new client */
}

static bool open_pty(const char *link)
{
    struct termios t;
    const char *slave;
    struct stat st;

    if (strlen(link) == 0u || strlen(link) >= sizeof link_path) {
        el_host_error("--debug pty:LINK: give the path of the link to make");
        return false;
    }
    if (lstat(link, &st) == 0 && !S_ISLNK(st.st_mode)) {
        el_host_error("--debug pty:%s: exists and is not a symbolic link; not replacing it", link);
        return false;
    }
    conn_fd = posix_openpt(O_RDWR | O_NOCTTY);
    if (conn_fd < 0 || grantpt(conn_fd) != 0 || unlockpt(conn_fd) != 0 || (slave = ptsname(conn_fd)) == NULL) {
        el_host_error("--debug pty:%s: cannot make a pseudo-terminal: %s", link, strerror(errno));
        return false;
    }
    keep_fd = open(slave, O_RDWR | O_NOCTTY);
    if (keep_fd < 0 || tcgetattr(keep_fd, &t) != 0) {
        el_host_error("--debug pty:%s: cannot open %s: %s", link, slave, strerror(errno));
        return false;
    }
    /* Raw bytes both ways (what cfmakeraw does). */
    t.c_iflag &= ~(tcflag_t)(IGNBRK | BRKINT | PARMRK | ISTRIP | INLCR | IGNCR | ICRNL | IXON);
    t.c_oflag &= ~(tcflag_t)OPOST;
    t.c_lflag &= ~(tcflag_t)(ECHO | ECHONL | ICANON | ISIG | IEXTEN);
    t.c_cflag &= ~(tcflag_t)(CSIZE | PARENB);
    t.c_cflag |= CS8;
    if (tcsetattr(keep_fd, TCSANOW, &t) != 0 || !set_nonblocking(conn_fd)) {
        el_host_error("--debug pty:%s: cannot set up %s: %s", link, slave, strerror(errno));
        return false;
    }
    set_conn(conn_fd);
    (void)unlink(link);
    if (symlink(slave, link) != 0) {
        el_host_error("--debug pty:%s: cannot make the link: %s", link, strerror(errno));
        return false;
    }
    strcpy(link_path, link);
    link_made = true;
    atexit(remove_link);
    return true;
}

static bool open_tcp(const char *port_text)
{
    listen_fd = el_host_listen_tcp("--debug", port_text, "debug interface");
    return listen_fd >= 0;
}

/* After a reset: take over the descriptors of the process we replaced. */
static bool adopt(const char *spec, bool *halt)
{
    const char *fds = getenv(FDS_ENV), *h = getenv(HALT_ENV);
    int kind, a, b;
    char tail;
    if (fds == NULL)
        return false;
    if (sscanf(fds, "%d:%d:%d%c", &kind, &a, &b, &tail) != 3 || (kind != PTY && kind != TCP) ||
        fcntl(a, F_GETFD) < 0 || (b >= 0 && fcntl(b, F_GETFD) < 0) || (kind == PTY) != (strncmp(spec, "pty:", 4) == 0))
        return false;
    mode = kind == PTY ? PTY : TCP;
    if (mode == PTY) {
        conn_fd = a;
        keep_fd = b;
        if (strlen(spec + 4) < sizeof link_path) {
            strcpy(link_path, spec + 4);
            link_made = true;
            atexit(remove_link);
        }
    } else {
        listen_fd = a;
        conn_fd = b;
    }
    set_conn(conn_fd);
    *halt = h != NULL && strcmp(h, "1") == 0;
    (void)unsetenv(FDS_ENV);
    (void)unsetenv(HALT_ENV);
    return true;
}

bool el_host_opt_debug(const char *arg)
{
    char spec[4200];
    size_t n = strlen(arg);
    bool halt = false, adopted;

    if (n >= sizeof spec) {
        el_host_error("--debug: argument too long");
        return false;
    }
    strcpy(spec, arg);
    if (n >= 5u && strcmp(spec + n - 5u, ",halt") == 0) {
        spec[n - 5u] = '\0';
        halt = true;
    }
    adopted = adopt(spec, &halt);
    if (!adopted) {
        if (strncmp(spec, "pty:", 4) == 0) {
            mode = PTY;
            if (!open_pty(spec + 4))
                return false;
        } else if (strncmp(spec, "tcp:", 4) == 0) {
            mode = TCP;
            if (!open_tcp(spec + 4))
                return false;
        } else {
            el_host_error("--debug %s: give pty:LINK or tcp:PORT (optionally followed by ,halt)", arg);
            return false;
        }
    }
    if ((mode == PTY && !el_host_watch_fd(conn_fd, on_conn, NULL)) ||
        (mode == TCP && !el_host_watch_fd(listen_fd, on_listen, NULL)) ||
        (mode == TCP && conn_fd >= 0 && !el_host_watch_fd(conn_fd, on_conn, NULL)))
        return false;
    chain_signals();
    if (halt)
        el_debug_halt_at_start();
    return true;
}

/* ---- el_debug.h: the board's side ---- */

uint16_t el_debug_port_read(uint8_t *buf, uint16_t max)
{
    ssize_t r;
    if (conn_fd < 0 || max == 0u)
        return 0u;
    r = read(conn_fd, buf, max);
    if (r > 0)
        return (uint16_t)r;
    if (r == 0 && mode == TCP) /* the client closed */
        drop_client();
    return 0u;
}

/* Never waits for the debugger (docs/protocol.md, "A debugger that does
 * not read"): false drops the response, which the server counts. */
bool el_debug_port_write(const uint8_t *frame, uint16_t len)
{
    uint8_t r;
    if (conn_fd < 0)
        return false;
    r = el_host_out_put(&out, frame, len);
    if (r == EL_HOST_OUT_SENT) {
        reads_again();
        return true;
    }
    if (mode == TCP) {
        if (r == EL_HOST_OUT_FULL)
            el_host_error("debug interface: the client does not read its responses: dropped");
        drop_client(); /* the next client is served */
    } else if (!dropping) {
        dropping = true;
        el_host_error("debug interface: the debugger does not read its responses on %s: they are dropped "
                      "(counted: tx_dropped) until it reads again", link_path);
    }
    return false;
}

static char **read_cmdline(void)
{
    static char buf[65536];
    static char *args[1024];
    size_t n = 0, i, argc = 0;
    FILE *f = fopen("/proc/self/cmdline", "rb");
    if (f == NULL)
        return NULL;
    n = fread(buf, 1, sizeof buf - 1u, f);
    fclose(f);
    buf[n] = '\0';
    for (i = 0; i < n && argc + 1u < sizeof args / sizeof args[0]; i++) {
        if (i == 0 || buf[i - 1] == '\0')
            args[argc++] = &buf[i];
    }
    args[argc] = NULL;
    return argc > 0 ? args : NULL;
}

static bool keep_on_exec(int fd)
{
    int flags;
    if (fd < 0)
        return true;
    flags = fcntl(fd, F_GETFD);
    return flags >= 0 && fcntl(fd, F_SETFD, flags & ~FD_CLOEXEC) == 0;
}

bool el_host_debug_handover(uint8_t flags)
{
    char fds[64];
    (void)el_host_out_drain(&out, 100); /* the last responses; a debugger that does not read loses them */
    snprintf(fds, sizeof fds, "%d:%d:%d", (int)mode, mode == PTY ? conn_fd : listen_fd,
             mode == PTY ? keep_fd : conn_fd);
    if (!keep_on_exec(conn_fd) || !keep_on_exec(keep_fd) || !keep_on_exec(listen_fd) ||
        setenv(FDS_ENV, fds, 1) != 0 || setenv(HALT_ENV, (flags & EL_DBG_RESET_HALT) != 0u ? "1" : "0", 1) != 0) {
        el_host_error("debug interface: cannot hand it over: %s", strerror(errno));
        return false;
    }
    link_made = false; /* the next program keeps the link */
    return true;
}

bool el_debug_port_reset(uint8_t flags)
{
    char **args = read_cmdline();
    if (args == NULL) {
        el_host_error("debug reset: cannot read the command line");
        return false;
    }
    if (!el_host_debug_handover(flags))
        return false;
    fflush(NULL);
    execv("/proc/self/exe", args);
    el_host_error("debug reset: cannot restart %s: %s", args[0], strerror(errno));
    (void)unsetenv(FDS_ENV);
    link_made = true;
    return false;
}

#else /* no debug server in this build */

bool el_host_opt_debug(const char *arg)
{
    (void)arg;
#if defined(EL_DEBUG) && EL_DEBUG
    el_host_error("--debug: model %s has no debug interface (declare one: `debug on uart0`)", el_model_name);
#else
    el_host_error("--debug: this is a release build, which has no debug interface");
#endif
    return false;
}

#endif /* EL_DEBUG_SERVER */
