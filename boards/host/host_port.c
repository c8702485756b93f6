/* EasyLab host board: the port interface of runtime_c/el_port.h on POSIX.
 *
 * Time: with --fast, virtual (el_port_wait_tick returns at once); without,
 * tick n is due n * el_tick_us microseconds after the first
 * el_port_wait_tick call, on CLOCK_MONOTONIC (clock_nanosleep with
 * TIMER_ABSTIME, so lateness does not accumulate). --duration T ends the
 * run at the first tick whose time is >= T (a real-time run sleeps until
 * T first, so it lasts T). SIGINT and SIGTERM end the run at the next
 * el_port_wait_tick, so the dispatcher shuts down normally (trace flushed)
 * and the process exits with status 0.
 */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif

#include "host_internal.h"
#include "el_dispatch.h"
#if defined(EL_REMOTE_PROXY) && EL_REMOTE_PROXY
#include "el_remote.h"
#endif

#include <errno.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

const char *el_host_prog = "easylab-host";

static int exit_status = EL_HOST_EXIT_OK;
static bool running;            /* el_port_init succeeded, no shutdown yet */
static volatile sig_atomic_t stop_signal;

/* Logical time: the ticks given to el_port_wait_tick (32 bits, wrapping)
 * extended to 64 bits. */
static bool have_tick;
static uint32_t last_tick32;
static uint64_t tick64;         /* the tick being processed */
static uint64_t first_tick64;   /* the first tick: due at start_ns */
static uint64_t now_us;         /* tick64 * el_tick_us */

/* Real time: CLOCK_MONOTONIC at the first el_port_wait_tick, in ns. */
static uint64_t start_ns;

/* Critical-section nesting (no interrupts on the host: bookkeeping only). */
static el_irq_state_t irq_disabled;

int el_host_exit_status(void)
{
    return exit_status;
}

bool el_host_stop_requested(void)
{
    return stop_signal != 0;
}

uint64_t el_host_now_us(void)
{
    return now_us;
}

/* ---- checks of the generated tables (a generator bug, not a user error) ---- */

static bool check_model(void)
{
    uint16_t i;
    uint8_t c;
    if (el_tick_us == 0u) {
        el_host_error("model tables: el_tick_us is 0");
        return false;
    }
    for (i = 0; i < el_item_count; i++) {
        const el_item_t *it = &el_items[i];
        if (it->name == NULL || it->name[0] == '\0' || el_host_type_size(it->type) == 0u || it->kind > EL_K_DEV_IN ||
            it->count == 0u || it->addr == NULL) {
            el_host_error("model tables: el_items[%u] is malformed", (unsigned)i);
            return false;
        }
        if ((it->kind == EL_K_DEV_OUT || it->kind == EL_K_DEV_IN) && it->device >= el_device_count) {
            el_host_error("model tables: el_items[%u] (%s) has no valid device", (unsigned)i, it->name);
            return false;
        }
    }
    for (c = 0; c < el_chart_count; c++) {
        const el_chart_t *ch = &el_charts[c];
        uint8_t s;
        if (ch->name == NULL || (ch->step_count > 0u && (ch->step_names == NULL || ch->active == NULL))) {
            el_host_error("model tables: el_charts[%u] is malformed", (unsigned)c);
            return false;
        }
        for (s = 0; s < ch->step_count; s++)
            if (ch->step_names[s] == NULL) {
                el_host_error("model tables: el_charts[%u] has a step without a name", (unsigned)c);
                return false;
            }
    }
    return true;
}

/* ---- signals ---- */

static struct sigaction default_action; /* SIG_DFL, set up before use */

static void on_stop_signal(int sig)
{
    stop_signal = sig;
    /* A second signal kills at once (sigaction is async-signal-safe). */
    sigaction(sig, &default_action, NULL);
}

static void install_signals(void)
{
    struct sigaction sa;
    memset(&default_action, 0, sizeof default_action);
    sigemptyset(&default_action.sa_mask);
    default_action.sa_handler = SIG_DFL;
    memset(&sa, 0, sizeof sa);
    sigemptyset(&sa.sa_mask);
    sa.sa_handler = on_stop_signal;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    /* A trace on a closed pipe: report EPIPE instead of dying silently. */
    sa.sa_handler = SIG_IGN;
    sa.sa_flags = 0;
    sigaction(SIGPIPE, &sa, NULL);
}

/* ---- init and shutdown ---- */

#if defined(EL_HOST_DDS)
#include "host_dds.h" /* a node with DDS exports or channels (docs/distribution.md) */
#define DDS_START() el_host_dds_start()
#define DDS_STOP() el_host_dds_stop()
#define DDS_INPUTS(now_us) el_host_dds_inputs(now_us)
#else
#define DDS_START() true
#define DDS_STOP() ((void)0)
#define DDS_INPUTS(now_us) ((void)(now_us))
#endif

static void release_all(void)
{
    DDS_STOP();
    if (!el_host_trace_close())
        exit_status = EL_HOST_EXIT_IO;
    el_host_stimulus_free();
    el_host_nv_close();
}

bool el_port_init(int argc, char **argv)
{
    int r;

    if (argc > 0 && argv != NULL && argv[0] != NULL && argv[0][0] != '\0') {
        const char *slash = strrchr(argv[0], '/');
        el_host_prog = slash ? slash + 1 : argv[0];
    }
    exit_status = EL_HOST_EXIT_OK;
    running = false;
    have_tick = false;
    tick64 = first_tick64 = now_us = 0;
    irq_disabled = 0;

    /* From here on a SIGINT or SIGTERM ends the run at its first tick. */
    stop_signal = 0;
    install_signals();
    if (!check_model()) {
        exit_status = EL_HOST_EXIT_USAGE;
        return false;
    }
    r = el_host_parse_args(argc, argv);
    if (r != EL_HOST_ARGS_RUN) {
        exit_status = r == EL_HOST_ARGS_DONE ? EL_HOST_EXIT_OK : EL_HOST_EXIT_USAGE;
        return false;
    }
    /* Inputs first, then the trace: a failed run creates no trace file. */
    if ((el_host_settings.stimulus_path != NULL && !el_host_stimulus_load(el_host_settings.stimulus_path)) ||
        !el_host_nv_open(el_host_settings.nvram_path) ||
        (el_host_settings.trace_path != NULL && !el_host_trace_open(el_host_settings.trace_path)) ||
        !DDS_START()) {
        release_all();
        exit_status = EL_HOST_EXIT_USAGE;
        return false;
    }
    running = true;
    return true;
}

#if defined(EL_REMOTE_PROXY) && EL_REMOTE_PROXY
/* A proxy's tasks run on the host (easylab remote): an overrun is a
 * deadline at which the host's values had not come, as `easylab remote`
 * reports it; the dispatcher's count is the proxy's own lateness. */
#define OWN_LATENESS "behind its clock (instants processed after their deadlines):"
static void report_remote_overruns(void)
{
    uint8_t i;
    bool any = false;
    for (i = 0; i < el_task_count; i++)
        if (el_remote_overruns(i) != 0u)
            any = true;
    if (!any)
        return;
    fprintf(stderr, "%s: overruns:", el_host_prog);
    for (i = 0; i < el_task_count; i++)
        if (el_remote_overruns(i) != 0u)
            fprintf(stderr, " %s %u", el_task_names[i] ? el_task_names[i] : "?", (unsigned)el_remote_overruns(i));
    fputs(" (the host's values came late; the previous values held)\n", stderr);
}
#else
#define OWN_LATENESS "overruns:"
static void report_remote_overruns(void)
{
}
#endif

void el_port_shutdown(void)
{
    uint8_t i;
    bool any = false;

    if (!running)
        return;
    running = false;
    release_all();
    for (i = 0; i < el_task_count; i++)
        if (el_overruns[i] != 0u)
            any = true;
    if (any) {
        fprintf(stderr, "%s: %s", el_host_prog, OWN_LATENESS);
        for (i = 0; i < el_task_count; i++)
            if (el_overruns[i] != 0u)
                fprintf(stderr, " %s %u", el_task_names[i] ? el_task_names[i] : "?", (unsigned)el_overruns[i]);
        fputc('\n', stderr);
    }
    report_remote_overruns();
    el_host_bus_report();
    fflush(stderr);
}

/* ---- time ---- */

static uint64_t monotonic_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000000u + (uint64_t)ts.tv_nsec;
}

/* Sleep until CLOCK_MONOTONIC reads `deadline_ns`, serving the watched
 * descriptors meanwhile; false if a stop signal came. */
static bool sleep_until(uint64_t deadline_ns)
{
    struct timespec ts;
    int r;
    for (;;) {
        uint64_t now = monotonic_ns();
        if (stop_signal)
            return false;
        if (now >= deadline_ns || !el_host_watching())
            break;
        /* poll() counts whole milliseconds: leave the last one to
         * clock_nanosleep so that instants stay exact, but look at the
         * descriptors at least once per instant (ticks of 1 ms or less). */
        if (deadline_ns - now <= 1000000u) {
            el_host_serve_fds(0);
            break;
        }
        el_host_serve_fds((int)((deadline_ns - now - 1000000u) / 1000000u));
    }
    ts.tv_sec = (time_t)(deadline_ns / 1000000000u);
    ts.tv_nsec = (long)(deadline_ns % 1000000000u);
    do {
        if (stop_signal)
            return false;
        r = clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL);
    } while (r == EINTR);
    return !stop_signal;
}

static uint64_t mul_sat(uint64_t a, uint64_t b)
{
    return (b != 0u && a > UINT64_MAX / b) ? UINT64_MAX : a * b;
}

#if defined(EL_ROUND_MASTER)
/* The master of a Modbus round (docs/distribution.md; the node's generated
 * el_link.c defines it, and the build defines EL_ROUND_MASTER) runs the
 * round's events due by each instant, and at the end of a run those before
 * its end. */
void el_round_master(uint64_t until_us, bool inclusive);
#define ROUND_MASTER(until_us, inclusive) el_round_master((until_us), (inclusive))
#else
#define ROUND_MASTER(until_us, inclusive) ((void)(until_us), (void)(inclusive))
#endif

bool el_port_wait_tick(uint32_t tick)
{
    uint64_t t64, t_us;

    if (stop_signal)
        return false;
    if (!have_tick) {
        have_tick = true;
        t64 = tick;
        first_tick64 = t64;
        if (!el_host_settings.fast)
            start_ns = monotonic_ns();
    } else {
        t64 = tick64 + (uint32_t)(tick - last_tick32);
    }
    last_tick32 = tick;
    t_us = mul_sat(t64, el_tick_us);

    if (el_host_settings.has_duration && t_us >= el_host_settings.duration_us) {
        ROUND_MASTER(el_host_settings.duration_us, false);
        if (!el_host_settings.fast) {
            uint64_t first_us = mul_sat(first_tick64, el_tick_us);
            if (el_host_settings.duration_us > first_us)
                (void)sleep_until(start_ns + mul_sat(el_host_settings.duration_us - first_us, 1000u));
        }
        return false;
    }
    tick64 = t64;
    now_us = t_us;
    if (!el_host_settings.fast)
        return sleep_until(start_ns + mul_sat(mul_sat(t64 - first_tick64, el_tick_us), 1000u));
    el_host_serve_fds(0); /* virtual time: answer what is there, never wait */
    return !stop_signal;
}

void el_port_resync(void)
{
    /* The current tick is due now: real time resumes from here. */
    if (!el_host_settings.fast && have_tick)
        start_ns = monotonic_ns() - mul_sat(mul_sat(tick64 - first_tick64, el_tick_us), 1000u);
}

uint32_t el_port_real_tick(void)
{
    if (el_host_settings.fast || !have_tick)
        return (uint32_t)tick64;
    return (uint32_t)(first_tick64 + (monotonic_ns() - start_ns) / 1000u / el_tick_us);
}

/* ---- critical sections: nothing to mask on a single-threaded host ---- */

el_irq_state_t el_port_irq_save(void)
{
    el_irq_state_t previous = irq_disabled;
    irq_disabled = 1;
    return previous;
}

void el_port_irq_restore(el_irq_state_t state)
{
    irq_disabled = state;
}

/* ---- instants ---- */

void el_port_inputs(uint64_t tick)
{
    ROUND_MASTER(mul_sat(tick, el_tick_us), true);
    DDS_INPUTS(mul_sat(tick, el_tick_us));
    el_host_stimulus_inputs();
}

void el_port_instant(uint64_t tick)
{
    if (running)
        el_host_trace_instant(tick);
}

/* ---- simulated devices ---- */

void el_sim_open(uint8_t device)
{
    (void)device;
}

void el_sim_close(uint8_t device)
{
    (void)device;
}

void el_sim_start(uint8_t device)
{
    (void)device;
}

void el_sim_stop(uint8_t device)
{
    (void)device;
}

void el_sim_write(uint8_t device)
{
    (void)device;
}
