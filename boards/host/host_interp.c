/* EasyLab host board: the port of local execution's interfaces library
 * (docs/local.md, "Debug and service interfaces").
 *
 * `easylab run` interprets a model in Python; its debug and service
 * interfaces are the firmware's own C servers (runtime_c/el_debug.c,
 * el_modbus.c, el_service.c) on the host board's transports
 * (host_debug.c, host_modbus.c, host_serve.c, host_nvram.c), built with
 * the model's generated tables and interp_interfaces.c into one shared
 * library per model and driven by generator/interp/interfaces.py through
 * the el_interp_* functions below. The interpreter owns time: it sets the
 * tick, calls the debugger's hooks at the firmware's points, and waits for
 * real time through el_interp_idle.
 *
 * The debug protocol's board commands (a new model for live replacement)
 * are in host_load.c.
 */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif

#include "host_internal.h"
#include "el_debug.h"
#include "el_dispatch.h"

const char *el_host_prog = "easylab run";

#define EL_INTERP_EXPORT __attribute__((visibility("default")))

static uint64_t now_tick;
static volatile uint8_t resync_pending;

/* ---- what the runtime asks of a board ---------------------------------------- */

uint64_t el_now_tick(void)
{
    return now_tick;
}

void el_idle(void)
{
    el_gen_interfaces_poll();
}

void el_port_resync(void)
{
    resync_pending = 1u; /* the interpreter's clock resumes from now */
}

/* ---- the interpreter's side ---------------------------------------------------- */

EL_INTERP_EXPORT bool el_interp_open(const char *debug, const char *modbus_tcp, const char *modbus_rtu,
                                     const char *nvram);
EL_INTERP_EXPORT void el_interp_set_tick(uint64_t tick);
EL_INTERP_EXPORT void el_interp_idle(uint16_t max_ms);
EL_INTERP_EXPORT uint8_t el_interp_take_resync(void);
EL_INTERP_EXPORT bool el_interp_has_debug(void);
EL_INTERP_EXPORT uint8_t el_interp_armed(void);
EL_INTERP_EXPORT void el_interp_instant(void);
EL_INTERP_EXPORT void el_interp_force(void);
EL_INTERP_EXPORT uint8_t el_interp_forcing(void);
EL_INTERP_EXPORT void el_interp_task_begin(uint8_t task);
EL_INTERP_EXPORT void el_interp_task_end(void);
EL_INTERP_EXPORT void el_interp_probe(uint8_t kind, uint16_t a, uint16_t b);
EL_INTERP_EXPORT void el_interp_abort_halt(void);
EL_INTERP_EXPORT bool el_interp_handover(void);
EL_INTERP_EXPORT void el_interp_close(void);

/* Open the transports given (NULL: none) and the non-volatile store, then
 * start the interfaces, as el_run does at boot. False after reporting. */
bool el_interp_open(const char *debug, const char *modbus_tcp, const char *modbus_rtu, const char *nvram)
{
    if (!el_host_nv_open(nvram))
        return false;
    if (debug != NULL && !el_host_opt_debug(debug))
        return false;
    if (modbus_tcp != NULL && !el_host_opt_modbus_tcp(modbus_tcp))
        return false;
    if (modbus_rtu != NULL && !el_host_opt_modbus_rtu(modbus_rtu))
        return false;
    el_gen_interfaces_boot();
    return true;
}

void el_interp_set_tick(uint64_t tick)
{
    now_tick = tick;
}

/* Serve the links for at most max_ms (0: what is there now). */
void el_interp_idle(uint16_t max_ms)
{
    el_host_serve_fds((int)max_ms);
}

uint8_t el_interp_take_resync(void)
{
    uint8_t r = resync_pending;
    resync_pending = 0u;
    return r;
}

/* Hand every link over to the library of the model replacing this one. */
bool el_interp_handover(void)
{
    bool ok = el_host_modbus_handover();
#if defined(EL_DEBUG_SERVER) && EL_DEBUG_SERVER
    ok = el_host_debug_handover(0u) && ok;
#endif
    return ok;
}

void el_interp_close(void)
{
    el_host_nv_close();
}

#if defined(EL_DEBUG_SERVER) && EL_DEBUG_SERVER

bool el_interp_has_debug(void)
{
    return true;
}

uint8_t el_interp_armed(void)
{
    return el_dbg_armed;
}

void el_interp_instant(void)
{
    el_debug_instant();
}

void el_interp_force(void)
{
    EL_DEBUG_FORCE(); /* forced values, conditional breakpoints: after the device reads */
}

uint8_t el_interp_forcing(void)
{
#if EL_DBG_HAS_FORCE_POINT
    return el_dbg_forcing;
#else
    return 0u;
#endif
}

void el_interp_task_begin(uint8_t task)
{
    el_debug_task_begin(task);
}

void el_interp_task_end(void)
{
    el_debug_task_end();
}

void el_interp_probe(uint8_t kind, uint16_t a, uint16_t b)
{
    el_debug_probe(kind, a, b);
}

void el_interp_abort_halt(void)
{
    el_debug_abort_halt = 1u;
}

#else /* the model has no debug interface */

bool el_interp_has_debug(void)
{
    return false;
}

uint8_t el_interp_armed(void)
{
    return 0u;
}

void el_interp_instant(void)
{
}

void el_interp_force(void)
{
}

uint8_t el_interp_forcing(void)
{
    return 0u;
}

void el_interp_task_begin(uint8_t task)
{
    (void)task;
}

void el_interp_task_end(void)
{
}

void el_interp_probe(uint8_t kind, uint16_t a, uint16_t b)
{
    (void)kind;
    (void)a;
    (void)b;
}

void el_interp_abort_halt(void)
{
}

#endif /* EL_DEBUG_SERVER */
