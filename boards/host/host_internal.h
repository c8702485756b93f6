/* EasyLab host board: declarations shared by the board's own files only
 * (host_port.c, host_serve.c, host_options.c, host_stimulus.c, host_trace.c,
 * host_nvram.c). Generated code includes el_board.h, never this.
 *
 * The host board is a POSIX program: unlike the runtime it may use the
 * heap, but only for data whose size comes from a file or from the model's
 * tables (stimulus events, trace columns), every allocation checked.
 */
#ifndef HOST_INTERNAL_H
#define HOST_INTERNAL_H

#include "el_types.h"
#include "el_model.h"
#include "el_port.h"
#include "el_board.h"

/* Longest line of a stimulus CSV file, in bytes, without its line end.
 * Longer lines are reported as errors, never truncated. */
#define EL_HOST_LINE_MAX 65536u

/* Most events (non-empty value cells) of a stimulus file: 4 Mi events of
 * 16 bytes, 64 MiB; a bigger file is reported, not loaded. The same bound
 * as easylab run's reader (generator/interp/stimulus.py, MAX_VALUES). */
#define EL_HOST_STIMULUS_MAX_EVENTS (4ul * 1024ul * 1024ul)

/* The declared ranges of the items that have one (host_ranges.c, written by
 * the host board's backend): a stimulus value outside is refused, as the
 * debug and service interfaces refuse such a write. Weak: a program built
 * without that table (a hand-written stand-in) checks no range. */
typedef struct {
    uint16_t item; /* index into el_items */
    double lo, hi; /* in run-time units (time: ms) */
} el_host_range_t;
extern const el_host_range_t el_host_ranges[]
#if defined(__GNUC__)
    __attribute__((weak))
#endif
    ;
extern const uint16_t el_host_range_count
#if defined(__GNUC__)
    __attribute__((weak))
#endif
    ;

/* Most descriptors (listening sockets, connections, ptys) served at once. */
#define EL_HOST_MAX_WATCHED 32u

/* ---- descriptors served between instants (host_serve.c) ---- */

/* Called when `fd` is readable or closed, or writable while output waits
 * (revents as poll() sets them). */
typedef void (*el_host_fd_handler_t)(int fd, short revents, void *ctx);

/* Serve `fd` between instants (while waiting in real time, at every
 * instant in virtual time, and while halted: el_port_idle). */
bool el_host_watch_fd(int fd, el_host_fd_handler_t handler, void *ctx);
void el_host_unwatch_fd(int fd);
/* Whether a watched `fd`'s handler also runs when it is writable (POLLOUT):
 * while output waits to be written without blocking the loop. */
void el_host_watch_output(int fd, bool want);
/* Wait at most timeout_ms (0: just look) for the watched descriptors, run
 * the handlers of those that are ready, then el_idle (the interfaces). */
void el_host_serve_fds(int timeout_ms);
/* Whether any descriptor is watched. */
bool el_host_watching(void);
/* Before a pty's master closes (it drops unread input then): wait, at most
 * 300 ms, until the reader has taken what we wrote; `slave` is our own
 * slave descriptor (-1: nothing to wait for). */
void el_host_drain_pty(int slave);

/* Output that never waits for its peer: bytes for a non-blocking
 * descriptor (a socket, a pty's master) go straight to it while nothing
 * waits; what the kernel does not take now waits in the link's own bounded
 * buffer, written when poll() says there is room (the descriptor's handler
 * calls el_host_out_flush when it is writable). A frame that does not fit
 * is refused whole, none of it written: the peer does not read, and each
 * link decides what that means (docs/protocol.md, docs/remote.md,
 * docs/service.md). */
typedef struct {
    int fd;         /* -1: none */
    bool is_socket; /* send(MSG_NOSIGNAL): a peer gone is an error, not a SIGPIPE */
    uint16_t len;   /* bytes waiting in data */
    uint16_t cap;   /* size of data */
    uint8_t *data;  /* the link's own static buffer */
} el_host_out_t;

#define EL_HOST_OUT_SENT 0u   /* written, or waiting in the buffer */
#define EL_HOST_OUT_FULL 1u   /* the peer does not read: the frame is refused, none of it written */
#define EL_HOST_OUT_BROKEN 2u /* the connection is broken (or there is none) */

/* Start `o` on descriptor fd (-1: none), nothing waiting, with buffer
 * data[0 .. cap). */
void el_host_out_init(el_host_out_t *o, int fd, bool is_socket, uint8_t *data, uint16_t cap);
/* Write as much of what waits as the descriptor takes now, and watch for
 * room while some remains; false when the connection is broken. */
bool el_host_out_flush(el_host_out_t *o);
/* Send frame[0 .. len): EL_HOST_OUT_SENT, _FULL or _BROKEN. */
uint8_t el_host_out_put(el_host_out_t *o, const uint8_t *frame, uint16_t len);
/* At the end of a link's use (a stop, an exec), not in the loop: wait at
 * most max_ms for what waits to be written; whether it all was. */
bool el_host_out_drain(el_host_out_t *o, int max_ms);

/* Listen on 127.0.0.1:PORT for `option tcp:PORT` (port_text "0": any free
 * port, printed on stderr as "PROG: WHAT on 127.0.0.1:N"): a non-blocking
 * socket, closed on exec, or -1 after reporting the error. */
int el_host_listen_tcp(const char *option, const char *port_text, const char *what);
/* A client of a listener made by el_host_listen_tcp, non-blocking, without
 * Nagle's delay and with a send buffer of EL_HOST_TCP_SNDBUF bytes (the
 * kernel may double it); -1 when none could be taken. */
#define EL_HOST_TCP_SNDBUF 16384u
int el_host_accept_tcp(int listen_fd);

/* Whether a SIGINT or SIGTERM came: the run ends at the next tick, and
 * whatever waits between ticks (a proxy waiting for its host) stops. */
bool el_host_stop_requested(void);

/* ---- messages (host_port.c) ---- */

/* The program name used in messages: argv[0] without its directory. */
extern const char *el_host_prog;

/* "PROG: message\n" on stderr. */
void el_host_error(const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 1, 2)))
#endif
    ;

/* ---- settings from the command line (host_options.c) ---- */

typedef struct {
    bool fast;                  /* --fast: virtual time */
    bool has_duration;          /* --duration given */
    uint64_t duration_us;       /* --duration, in microseconds */
    const char *stimulus_path;  /* --stimulus, or NULL */
    const char *trace_path;     /* --trace, or NULL */
    const char *nvram_path;     /* --nvram, or NULL */
} el_host_settings_t;

extern el_host_settings_t el_host_settings;

/* One command-line option. To add one: write its handler (in the file of
 * the feature, declared here), add a row to el_host_options[] in
 * host_options.c, and act on what the handler stored in el_port_init. */
typedef struct {
    const char *name;      /* "--trace" */
    const char *arg_name;  /* "FILE" for `--trace FILE` / `--trace=FILE`; NULL for a flag */
    const char *help;      /* one line for --help */
    bool repeatable;       /* may be given more than once */
    /* Store the option (arg is NULL for a flag). Returns false after
     * reporting the error with el_host_error. */
    bool (*handle)(const char *arg);
} el_host_option_t;

extern const el_host_option_t el_host_options[];
extern const size_t el_host_option_count;

/* Results of el_host_parse_args. */
#define EL_HOST_ARGS_RUN 0    /* run the model */
#define EL_HOST_ARGS_DONE 1   /* --help was printed: exit with status 0 */
#define EL_HOST_ARGS_ERROR 2  /* an error was reported: exit with status 2 */
int el_host_parse_args(int argc, char **argv);

/* Parse a duration with a unit ("10s", "500ms", "250us", "1.5s", "2m",
 * "1h"; a space may separate number and unit) into exact microseconds.
 * On error returns false and sets *why to a message. */
bool el_host_parse_duration(const char *text, uint64_t *us, const char **why);

/* Write the params and vars a stimulus sets by now (host_stimulus.c). */
void el_host_stimulus_inputs(void);

/* host_bus.c: a Modbus round's master's lines; at the end of a run, the
 * frames each slave left unanswered (stderr). */
void el_host_bus_report(void);

/* ---- the model's tables (host_port.c) ---- */

/* Bytes of one value of an EL_T_ type (0 for an unknown type). */
size_t el_host_type_size(uint8_t type);
/* The language's name of an EL_T_ type: "int16", "float32", ... */
const char *el_host_type_name(uint8_t type);

/* Logical time, in microseconds, of the instant being processed: the tick
 * last accepted by el_port_wait_tick times el_tick_us (0 before). */
uint64_t el_host_now_us(void);

/* ---- stimulus (host_stimulus.c) ---- */

/* Load and check a stimulus file; errors are reported as FILE:LINE: ...
 * Returns false on error (nothing loaded). */
bool el_host_stimulus_load(const char *path);
void el_host_stimulus_free(void);
/* Whether the program reads the stimulus of an item (NULL, as on the host
 * board: every device `out` datum, param and var). A simulator harness
 * sets it: a device datum with nothing behind it in the simulation (no
 * hardware the harness drives, no chip model) reads no stimulus, and its
 * column is an error rather than a value dropped without a word. */
extern bool (*el_host_stimulus_reads)(uint16_t item);
/* Why the program does not read item's stimulus (with el_host_stimulus_reads). */
extern const char *el_host_stimulus_unread_why;
/* The loaded stimulus's events in order (for a simulator that replays it
 * inside a firmware): the row's time, the item, the elements it sets
 * (first, n) and one value (el_host_type_size bytes). False past the last. */
bool el_host_stimulus_event(size_t index, uint64_t *time_us, uint16_t *item, uint16_t *first, uint16_t *n,
                            void *value);

/* ---- trace (host_trace.c) ---- */

/* Create the trace file (.csv or .vcd) and write its header. */
bool el_host_trace_open(const char *path);
/* Record the values at logical tick `tick`. */
void el_host_trace_instant(uint64_t tick);
/* Flush and close; false if writing failed (reported). No-op if closed. */
bool el_host_trace_close(void);

/* ---- debug interface (host_debug.c) ---- */

/* The --debug option: open the pty or TCP port and serve it. */
bool el_host_opt_debug(const char *arg);
/* Hand the open debug link over to the next program (EL_DBG_RESET_HALT in
 * `flags`: it starts halted): this process after exec (the protocol's
 * RESET), or the interfaces library of a model that replaces this one in
 * local execution; the next el_host_opt_debug with the same spec adopts
 * it. False (reported) if it cannot. */
bool el_host_debug_handover(uint8_t flags);

/* ---- service interface (host_modbus.c, host_hmi.c; docs/service.md) ---- */

/* --modbus-tcp PORT, --modbus-rtu pty:LINK: where the model's Modbus
 * interfaces are served (opened when the option is read). */
bool el_host_opt_modbus_tcp(const char *arg);
bool el_host_opt_modbus_rtu(const char *arg);
/* Hand the Modbus links (listening socket, TCP clients, RTU pty) over to
 * the interfaces library of a model that replaces this one in local
 * execution; its --modbus-tcp / --modbus-rtu / `modbus tcp` adopt them. */
bool el_host_modbus_handover(void);
/* --hmi pty:LINK: the example HMI, a line protocol over el_service.h. */
bool el_host_opt_hmi(const char *arg);
bool el_host_opt_link(const char *arg); /* host_remote.c: a remote-execution proxy's link */
/* A pseudo-terminal with a symlink `link` to it (removed at exit): returns
 * its master and keeps our own slave descriptor in *slave_out (so the master
 * never sees a hangup between clients), or -1 after reporting the error
 * prefixed with `option`. */
int el_host_make_pty(const char *option, const char *link, int *slave_out);

/* ---- non-volatile storage (host_nvram.c) ---- */

/* Use the file at `path` (NULL: an in-memory store). */
bool el_host_nv_open(const char *path);
void el_host_nv_close(void);

#endif /* HOST_INTERNAL_H */
