/* EasyLab host board: the file descriptors served between instants (the
 * debug and Modbus transports, the HMI, a proxy's link), output that never
 * waits for its peer (el_host_out_*: the debug, remote and Modbus TCP
 * links), el_port_idle and the TCP listening sockets of the options that
 * take tcp:PORT.
 *
 * Shared by the host firmware (host_port.c waits for ticks through it) and
 * by the interfaces library of local execution (host_interp.c), which
 * serves the same transports for the interpreter.
 */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif

#include "host_internal.h"
#include "el_dispatch.h"

#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

/* ---- file descriptors served between instants ---- */

typedef struct {
    int fd;
    el_host_fd_handler_t handler;
    void *ctx;
    short events; /* POLLIN, with POLLOUT while output waits (el_host_watch_output) */
} watched_t;

static watched_t watched[EL_HOST_MAX_WATCHED];
static size_t watched_count;

bool el_host_watch_fd(int fd, el_host_fd_handler_t handler, void *ctx)
{
    if (watched_count >= EL_HOST_MAX_WATCHED) {
        el_host_error("too many open connections (at most %u)", (unsigned)EL_HOST_MAX_WATCHED);
        return false;
    }
    watched[watched_count].fd = fd;
    watched[watched_count].handler = handler;
    watched[watched_count].ctx = ctx;
    watched[watched_count].events = POLLIN;
    watched_count++;
    return true;
}

void el_host_watch_output(int fd, bool want)
{
    size_t i;
    for (i = 0; i < watched_count; i++) {
        if (watched[i].fd == fd) {
            watched[i].events = want ? (short)(POLLIN | POLLOUT) : (short)POLLIN;
            return;
        }
    }
}

void el_host_unwatch_fd(int fd)
{
    size_t i;
    for (i = 0; i < watched_count; i++) {
        if (watched[i].fd == fd) {
            watched[i] = watched[watched_count - 1u];
            watched_count--;
            return;
        }
    }
}

/* Wait at most timeout_ms (0: just look) for the watched descriptors and
 * run the handlers of those that are ready. */
void el_host_serve_fds(int timeout_ms)
{
    struct pollfd fds[EL_HOST_MAX_WATCHED];
    watched_t copy[EL_HOST_MAX_WATCHED];
    size_t i, n = watched_count;
    int r;
    if (n == 0u) {
        if (timeout_ms > 0) {
            struct timespec ts;
            ts.tv_sec = timeout_ms / 1000;
            ts.tv_nsec = (long)(timeout_ms % 1000) * 1000000L;
            (void)nanosleep(&ts, NULL);
        }
        el_idle();
        return;
    }
    for (i = 0; i < n; i++) {
        copy[i] = watched[i]; /* handlers may watch or unwatch */
        fds[i].fd = watched[i].fd;
        fds[i].events = watched[i].events;
        fds[i].revents = 0;
    }
    r = poll(fds, (nfds_t)n, timeout_ms);
    if (r > 0) {
        for (i = 0; i < n; i++) {
            if (fds[i].revents != 0)
                copy[i].handler(copy[i].fd, fds[i].revents, copy[i].ctx);
        }
    }
    el_idle();
}

bool el_host_watching(void)
{
    return watched_count != 0u;
}

void el_port_idle(uint16_t max_ms)
{
    el_host_serve_fds((int)max_ms);
}

/* ---- output that never waits for its peer ---- */

void el_host_out_init(el_host_out_t *o, int fd, bool is_socket, uint8_t *data, uint16_t cap)
{
    o->fd = fd;
    o->is_socket = is_socket;
    o->len = 0u;
    o->cap = cap;
    o->data = data;
}

/* Write what the descriptor takes now, never waiting: the number of bytes
 * written (0 when it takes none now), or -1 when the connection is broken. */
static int32_t write_now(const el_host_out_t *o, const uint8_t *data, uint16_t len)
{
    ssize_t n;
    do {
        n = o->is_socket ? send(o->fd, data, len, MSG_NOSIGNAL) : write(o->fd, data, len);
    } while (n < 0 && errno == EINTR);
    if (n >= 0)
        return (int32_t)n;
    return errno == EAGAIN || errno == EWOULDBLOCK ? 0 : -1;
}

bool el_host_out_flush(el_host_out_t *o)
{
    int32_t n;
    if (o->fd < 0)
        return false;
    if (o->len == 0u)
        return true;
    n = write_now(o, o->data, o->len);
    if (n < 0)
        return false;
    memmove(o->data, o->data + n, (size_t)(o->len - (uint16_t)n));
    o->len = (uint16_t)(o->len - (uint16_t)n);
    el_host_watch_output(o->fd, o->len > 0u);
    return true;
}

uint8_t el_host_out_put(el_host_out_t *o, const uint8_t *frame, uint16_t len)
{
    int32_t sent = 0;
    if (!el_host_out_flush(o))
        return EL_HOST_OUT_BROKEN;
    if (len > o->cap - o->len)
        return EL_HOST_OUT_FULL;
    if (o->len == 0u) { /* nothing waiting: straight to the descriptor, in order */
        sent = write_now(o, frame, len);
        if (sent < 0)
            return EL_HOST_OUT_BROKEN;
    }
    memcpy(o->data + o->len, frame + sent, (size_t)(len - (uint16_t)sent));
    o->len = (uint16_t)(o->len + (len - (uint16_t)sent));
    el_host_watch_output(o->fd, o->len > 0u);
    return EL_HOST_OUT_SENT;
}

bool el_host_out_drain(el_host_out_t *o, int max_ms)
{
    int waited;
    for (waited = 0; o->fd >= 0 && o->len > 0u && waited < max_ms; waited += 10) {
        struct pollfd p;
        p.fd = o->fd;
        p.events = POLLOUT;
        p.revents = 0;
        if (poll(&p, 1, 10) < 0 && errno != EINTR)
            break;
        if (!el_host_out_flush(o))
            return false;
    }
    return o->fd >= 0 && o->len == 0u;
}

void el_host_drain_pty(int slave)
{
    int i, pending = 0, idle = 0;
    for (i = 0; i < 60 && slave >= 0 && idle < 3; i++) {
        struct timespec ts = {0, 5000000L};
        (void)nanosleep(&ts, NULL); /* the kernel moves written bytes to the reader's queue meanwhile */
        if (ioctl(slave, FIONREAD, &pending) != 0)
            break;
        idle = pending == 0 ? idle + 1 : 0;
    }
}

int el_host_accept_tcp(int listen_fd)
{
    int client = accept(listen_fd, NULL, NULL), one = 1, fl, sndbuf = (int)EL_HOST_TCP_SNDBUF;
    if (client < 0)
        return -1;
    /* Frames are small and answer each other: no Nagle delay. A bounded
     * send buffer (no autotuning to megabytes): a peer that stops reading
     * fills it, and the link's own buffer behind it, within a bounded
     * number of frames, so the link notices (el_host_out_put). */
    if ((fl = fcntl(client, F_GETFL)) < 0 || fcntl(client, F_SETFL, fl | O_NONBLOCK) != 0 ||
        setsockopt(client, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one) != 0 ||
        setsockopt(client, SOL_SOCKET, SO_SNDBUF, &sndbuf, sizeof sndbuf) != 0) {
        (void)close(client);
        return -1;
    }
    return client;
}

int el_host_listen_tcp(const char *option, const char *port_text, const char *what)
{
    char *end;
    long port;
    int one = 1, fd, fl, fd_fl;
    struct sockaddr_in addr;
    socklen_t len = sizeof addr;

    errno = 0;
    port = strtol(port_text, &end, 10);
    if (port_text[0] == '\0' || *end != '\0' || errno != 0 || port < 0 || port > 65535) {
        el_host_error("%s tcp:%s: not a port number (0..65535)", option, port_text);
        return -1;
    }
    fd = socket(AF_INET, SOCK_STREAM, 0);
    memset(&addr, 0, sizeof addr);
    addr.sin_family = AF_INET;
    addr.sin_port = htons((uint16_t)port);
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (fd < 0 || setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one) != 0 ||
        bind(fd, (struct sockaddr *)&addr, sizeof addr) != 0 || listen(fd, 2) != 0 ||
        (fl = fcntl(fd, F_GETFL)) < 0 || fcntl(fd, F_SETFL, fl | O_NONBLOCK) != 0 ||
        (fd_fl = fcntl(fd, F_GETFD)) < 0 || fcntl(fd, F_SETFD, fd_fl | FD_CLOEXEC) != 0) {
        el_host_error("%s tcp:%s: cannot listen on 127.0.0.1:%s: %s", option, port_text, port_text, strerror(errno));
        if (fd >= 0)
            (void)close(fd);
        return -1;
    }
    if (port == 0 && getsockname(fd, (struct sockaddr *)&addr, &len) == 0) {
        fprintf(stderr, "%s: %s on 127.0.0.1:%u\n", el_host_prog, what, (unsigned)ntohs(addr.sin_port));
        fflush(stderr);
    }
    return fd;
}
