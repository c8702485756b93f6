/* EasyLab host board: the link of a remote-execution proxy
 * (runtime_c/el_remote.h, docs/remote.md).
 *
 *   --link pty:LINK   make a pseudo-terminal and a symlink LINK to it
 *                     (removed at exit); the host side (easylab remote
 *                     --target LINK) opens LINK
 *   --link tcp:PORT   listen on 127.0.0.1:PORT (0: any free port, printed
 *                     on stderr); the host side connects with --target
 *                     socket://127.0.0.1:PORT. One host at a time: a new
 *                     connection replaces the old one (the watchdog covers
 *                     the gap in real time)
 *
 * Frames are never waited for (el_host_out_put): what the kernel does not
 * take now waits in a buffer of EL_HOST_LINK_OUT bytes, written when there
 * is room. A host that does not read its frames is a link failure
 * (docs/remote.md, "A host that does not read"), said once on stderr: over
 * TCP its connection is closed; on the pty the link is down, its frames
 * dropped and its requests ignored, until the host has read what waits.
 * Either way no valid frame comes, and the proxy's watchdog applies the
 * safe values, as when the host is gone.
 *
 * Only a proxy build (easylab proxy: -DEL_REMOTE_PROXY=1) has a link; in
 * other firmware the option says so. STOP from the host ends the run at
 * the next tick, as SIGTERM does (the safe values are applied first).
 */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif

#include "host_internal.h"

#if defined(EL_REMOTE_PROXY) && EL_REMOTE_PROXY

#include "el_remote.h"

#include <errno.h>
#include <poll.h>
#include <signal.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

/* Frame bytes waiting for the host to read (at least two of the longest
 * encoded frame). */
#define EL_HOST_LINK_OUT 1024u
#if EL_HOST_LINK_OUT < 2u * (EL_RMT_MAX_FRAME + 8u)
#error "EL_HOST_LINK_OUT must hold two of the longest frames"
#endif

static int conn_fd = -1;   /* pty master, or the host's TCP connection */
static int keep_fd = -1;   /* pty: our own slave descriptor (no hangup between clients) */
static int listen_fd = -1; /* TCP */
static el_host_out_t out;  /* frames waiting for room on conn_fd */
static uint8_t out_data[EL_HOST_LINK_OUT];
static bool failed;        /* pty: the host does not read: the link is down until it has read what waits */

/* conn_fd (-1: none) is the host's link from now on. */
static void set_conn(int fd)
{
    conn_fd = fd;
    el_host_out_init(&out, fd, listen_fd >= 0, out_data, (uint16_t)sizeof out_data);
}

static void drop_conn(void)
{
    el_host_unwatch_fd(conn_fd);
    (void)close(conn_fd);
    set_conn(-1);
}

/* The host does not read its frames: a link failure (said once). */
static void link_failure(void)
{
    if (listen_fd >= 0) {
        el_host_error("link: the host does not read its frames: link failure, its connection is closed "
                      "(the watchdog applies the safe values)");
        drop_conn();
        return;
    }
    failed = true;
    out.len = 0u; /* stale frames */
    el_host_watch_output(conn_fd, false);
    el_host_error("link: the host does not read its frames: link failure, frames are dropped and requests "
                  "ignored until it reads (the watchdog applies the safe values)");
}

/* pty: whether the link is down, after checking whether the host has read
 * everything that waits for it (the link is back then). */
static bool link_down(void)
{
    int pending = 0;
    if (!failed)
        return false;
    if (ioctl(keep_fd, FIONREAD, &pending) != 0 || pending != 0)
        return true;
    failed = false;
    el_host_error("link: the host reads its frames again: the link is back");
    return false;
}

static void on_conn(int fd, short revents, void *ctx)
{
    (void)fd;
    (void)ctx; /* bytes are taken by el_remote_poll (from el_idle, right after this) */
    if ((revents & POLLOUT) != 0 && !el_host_out_flush(&out) && listen_fd >= 0) {
        drop_conn(); /* broken */
        return;
    }
    if (listen_fd >= 0 && (revents & (POLLHUP | POLLERR | POLLNVAL)) != 0 && (revents & POLLIN) == 0)
        drop_conn(); /* the host closed the connection */
}

static void on_listen(int fd, short revents, void *ctx)
{
    int client;
    (void)ctx;
    if ((revents & POLLIN) == 0 || (client = el_host_accept_tcp(fd)) < 0)
        return;
    if (conn_fd >= 0)
        drop_conn(); /* a new host replaces the old one */
    set_conn(client);
    if (!el_host_watch_fd(client, on_conn, NULL)) {
        (void)close(client);
        set_conn(-1);
    }
}

bool el_host_opt_link(const char *arg)
{
    if (strncmp(arg, "pty:", 4) == 0 && arg[4] != '\0') {
        set_conn(el_host_make_pty("--link", arg + 4, &keep_fd));
        return conn_fd >= 0 && el_host_watch_fd(conn_fd, on_conn, NULL);
    }
    if (strncmp(arg, "tcp:", 4) == 0) {
        listen_fd = el_host_listen_tcp("--link", arg + 4, "link");
        return listen_fd >= 0 && el_host_watch_fd(listen_fd, on_listen, NULL);
    }
    el_host_error("--link %s: give pty:LINK or tcp:PORT", arg);
    return false;
}

uint16_t el_remote_port_read(uint8_t *buf, uint16_t max)
{
    ssize_t r;
    if (conn_fd < 0 || max == 0u)
        return 0u;
    r = read(conn_fd, buf, max);
    if (listen_fd >= 0 && (r == 0 || (r < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)))
        drop_conn(); /* the host closed the connection, or it broke */
    if (link_down())
        return 0u; /* the requests of a host that does not read are ignored */
    return r > 0 ? (uint16_t)r : 0u;
}

bool el_remote_port_write(const uint8_t *frame, uint16_t len)
{
    uint8_t r;
    if (conn_fd < 0 || link_down())
        return false;
    r = el_host_out_put(&out, frame, len);
    if (r == EL_HOST_OUT_FULL)
        link_failure();
    else if (r == EL_HOST_OUT_BROKEN && listen_fd >= 0)
        drop_conn(); /* the host went away */
    return r == EL_HOST_OUT_SENT;
}

bool el_remote_port_stopping(void)
{
    return el_host_stop_requested();
}

void el_remote_port_end(void)
{
    (void)el_host_out_drain(&out, 100); /* STOP's answer (the run ends: no loop to keep) */
    el_host_drain_pty(keep_fd); /* the host reads STOP's answer before the pty goes */
    if (listen_fd >= 0 && conn_fd >= 0)
        (void)shutdown(conn_fd, SHUT_WR); /* STOP's answer, then the end of the stream */
    (void)raise(SIGTERM); /* the port ends the run at the next tick */
}

#else

bool el_host_opt_link(const char *arg)
{
    (void)arg;
    el_host_error("--link: this program is not a remote-execution proxy (easylab proxy builds one)");
    return false;
}

#endif
