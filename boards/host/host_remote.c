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
#include <sys/socket.h>
#include <unistd.h>

static int conn_fd = -1;   /* pty master, or the host's TCP connection */
static int keep_fd = -1;   /* pty: our own slave descriptor (no hangup between clients) */
static int listen_fd = -1; /* TCP */

static void drop_conn(void)
{
    el_host_unwatch_fd(conn_fd);
    (void)close(conn_fd);
    conn_fd = -1;
}

static void on_conn(int fd, short revents, void *ctx)
{
    (void)fd;
    (void)ctx; /* bytes are taken by el_remote_poll (from el_idle, right after this) */
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
    conn_fd = client;
    if (!el_host_watch_fd(client, on_conn, NULL)) {
        (void)close(client);
        conn_fd = -1;
    }
}

bool el_host_opt_link(const char *arg)
{
    if (strncmp(arg, "pty:", 4) == 0 && arg[4] != '\0') {
        conn_fd = el_host_make_pty("--link", arg + 4, &keep_fd);
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
    return r > 0 ? (uint16_t)r : 0u;
}

bool el_remote_port_write(const uint8_t *frame, uint16_t len)
{
    size_t done = 0u;
    int tries = 0;
    while (conn_fd >= 0 && done < len) {
        /* A socket whose host went away fails with EPIPE, never SIGPIPE. */
        ssize_t w = listen_fd >= 0 ? send(conn_fd, frame + done, len - done, MSG_NOSIGNAL)
                                   : write(conn_fd, frame + done, len - done);
        if (w > 0) {
            done += (size_t)w;
            continue;
        }
        if ((w < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) || ++tries > 10)
            return false; /* a host that does not read: the frame is dropped (its CRC guards the rest) */
        {
            struct pollfd p;
            p.fd = conn_fd;
            p.events = POLLOUT;
            p.revents = 0;
            (void)poll(&p, 1, 10);
        }
    }
    return done == len;
}

bool el_remote_port_stopping(void)
{
    return el_host_stop_requested();
}

void el_remote_port_end(void)
{
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
