/* EasyLab runtime: the debug server (docs/protocol.md) and its hooks.
 *
 * Debug builds only. A release build (EL_RELEASE) compiles none of the
 * server (build.py leaves out runtime_c/el_debug*.c) and every hook below
 * is an empty macro. In a debug build the generator writes
 * el_debug_config.h beside model.c: EL_DEBUG_SERVER is 1 when the model
 * declares a debug interface (`debug on uart0`), else 0 and the hooks are
 * empty too.
 *
 * What the runtime and generated code call:
 *   EL_DEBUG_INSTANT()          dispatcher, after the inputs of an instant
 *   EL_DEBUG_FORCE()            dispatcher, after the devices are read,
 *                               before the tasks are released
 *   EL_DEBUG_TASK_BEGIN(task)   dispatcher, before a task's body
 *   EL_DEBUG_TASK_END(task)     dispatcher, after it
 *   EL_DEBUG_PROBE(kind, a, b)  model.c: chart evolutions, step
 *                               activations, transitions (EL_DBG_P_...)
 *   EL_DEBUG_PROBE_ACTOR(id)    model.c: an actor instance (its id in
 *                               the debug tables) fires
 * A probe costs one test of el_dbg_armed unless a breakpoint, a step or a
 * break request is pending.
 *
 * What a board provides when it carries the debug interface (the host
 * board: boards/host/host_debug.c):
 *   el_debug_port_read   take up to `max` received bytes, without waiting
 *   el_debug_port_write  send one encoded frame, or return false (dropped)
 *   el_debug_port_reset  restart the firmware from boot; returns only on
 *                        failure
 * and it calls el_port_idle/el_port_resync as el_port.h says.
 *
 * The frame given to el_debug_port_write is the server's response buffer,
 * and the server writes that buffer only while it handles a request, that
 * is when it meets a frame's delimiter (0x00); el_debug_poll asks
 * el_debug_port_read for one byte at a time, so it answers a request
 * before it reads the next byte. A board may therefore send straight from
 * the buffer, without copying it: its read must then return nothing while
 * a frame is still going out (the next request waits in its receive
 * buffer). A board that pushes bytes with el_debug_rx copies instead.
 */
#ifndef EL_DEBUG_H
#define EL_DEBUG_H

#include "el_types.h"

#if defined(EL_DEBUG) && EL_DEBUG && !(defined(EL_RELEASE) && EL_RELEASE)
#include "el_debug_config.h" /* generated: EL_DEBUG_SERVER */
#endif

#if defined(EL_DEBUG_SERVER) && EL_DEBUG_SERVER

#include "el_debug_protocol.h"

/* Forced elements and conditional breakpoints this server has room for:
 * el_debug_config.h says what the model asked for (0: the code is left
 * out); without it (the fuzz target), the protocol's most. */
#ifndef EL_DBG_FORCE_SLOTS
#define EL_DBG_FORCE_SLOTS EL_DBG_FORCE_MAX
#endif
#ifndef EL_DBG_COND_SLOTS
#define EL_DBG_COND_SLOTS EL_DBG_COND_MAX
#endif
#define EL_DBG_HAS_FORCE_POINT (EL_DBG_FORCE_SLOTS + EL_DBG_COND_SLOTS > 0)

/* ---- tables generated in debug_tables.c ---------------------------------- */

/* A range bound, in the item's type: i for signed types, u for unsigned
 * types, time and bool, f for float32. */
typedef union {
    int32_t i;
    uint32_t u;
    float f;
} el_dbg_bound_t;

typedef struct {
    el_dbg_bound_t lo;
    el_dbg_bound_t hi;
} el_dbg_range_t;

/* One debug item (docs/protocol.md "Items"): the model's items by their IR
 * ids, then the state variables of actor instances. */
typedef struct {
    void *addr;      /* `count` values of `type` */
    uint16_t count;
    uint16_t range;  /* index into el_dbg_ranges, or EL_DBG_NONE16 */
    uint8_t type;    /* EL_DBG_T_... */
    uint8_t kind;    /* EL_DBG_K_... */
    uint8_t flags;   /* EL_DBG_F_... */
} el_dbg_item_t;

/* One chart: its live continuation slots (the step each parallel branch
 * is in, EL_DBG_NONE8 for none). */
typedef struct {
    uint8_t *slots;
    uint8_t slot_count;
    uint8_t step_count;
    uint8_t transition_count;
} el_dbg_chart_t;

/* The arrays are read-only tables (EL_ROM: in flash where the board keeps
 * them there); the server reads them through EL_ROM_READ_U8. */
extern const el_dbg_item_t el_dbg_items[];
extern const uint16_t el_dbg_item_count;
extern const el_dbg_range_t el_dbg_ranges[];
extern const uint16_t el_dbg_actor_count;
extern const el_dbg_chart_t el_dbg_charts[];
extern const uint8_t el_dbg_chart_count;

/* ---- the server ------------------------------------------------------------ */

/* Bytes el_debug_poll takes from the board per call (bounds its work). */
#ifndef EL_DBG_POLL_BYTES
#define EL_DBG_POLL_BYTES 64u
#endif
/* How long one el_port_idle call of a halted program may wait, ms. */
#ifndef EL_DBG_IDLE_MS
#define EL_DBG_IDLE_MS 20u
#endif

/* Start the server (el_gen_interfaces_boot); boards call it again when a
 * new client connects: it resets the frame decoder and the memory of the
 * last request, not the program's halt state or breakpoints. */
void el_debug_boot(void);

/* Serve what the board received (el_gen_interfaces_poll, from el_idle):
 * at most EL_DBG_POLL_BYTES bytes, each complete request answered. */
void el_debug_poll(void);

/* Feed received bytes directly (boards that push bytes; the fuzzer). */
void el_debug_rx(const uint8_t *data, uint16_t len);

/* Halt at the first instant (before anything runs when called before
 * el_run's first instant). */
void el_debug_halt_at_start(void);

/* Set from a signal handler or an interrupt to let a halted program go
 * (shutting down): disarms every breakpoint and step for good. */
extern volatile uint8_t el_debug_abort_halt;

/* Nonzero when a probe must call into the server. */
extern uint8_t el_dbg_armed;

void el_debug_instant(void);
void el_debug_task_begin(uint8_t task);
void el_debug_task_end(void);
void el_debug_probe(uint8_t kind, uint16_t a, uint16_t b);
#if EL_DBG_HAS_FORCE_POINT
/* After an instant's device reads, before its tasks are released: the
 * forced elements get their values again, then the conditional
 * breakpoints are evaluated (a halt there is at EL_DBG_P_CONDITION).
 * Called only while el_dbg_forcing is nonzero (something forced or a
 * condition set). */
void el_debug_force(void);
extern uint8_t el_dbg_forcing;
#endif

/* ---- provided by the board's debug transport --------------------------- */
uint16_t el_debug_port_read(uint8_t *buf, uint16_t max);
bool el_debug_port_write(const uint8_t *frame, uint16_t len);
bool el_debug_port_reset(uint8_t flags);

/* Board commands (EL_DBG_CMD_BOARD_FIRST..LAST), for boards that define
 * EL_DEBUG_BOARD_COMMANDS to 1 (local execution's interfaces library):
 * the board runs the request and appends its response payload with
 * el_debug_put (false when it does not fit); it returns the status. */
#if defined(EL_DEBUG_BOARD_COMMANDS) && EL_DEBUG_BOARD_COMMANDS
uint8_t el_debug_port_command(uint8_t cmd, const uint8_t *payload, uint16_t n);
bool el_debug_put(const uint8_t *data, uint16_t n);
#endif

#define EL_DEBUG_INSTANT() el_debug_instant()
#define EL_DEBUG_TASK_BEGIN(task) el_debug_task_begin(task)
#if EL_DBG_HAS_FORCE_POINT
#define EL_DEBUG_FORCE() \
    do { if (el_dbg_forcing != 0u) { el_debug_force(); } } while (0)
#else
#define EL_DEBUG_FORCE() ((void)0)
#endif
#define EL_DEBUG_TASK_END(task) el_debug_task_end()
#define EL_DEBUG_PROBE(kind, a, b) \
    do { if (el_dbg_armed != 0u) { el_debug_probe((kind), (a), (b)); } } while (0)
#define EL_DEBUG_PROBE_ACTOR(actor) EL_DEBUG_PROBE(EL_DBG_P_ACTOR, (actor), 0u)

#else /* no debug server: the hooks compile to nothing */

#define EL_DEBUG_INSTANT() ((void)0)
#define EL_DEBUG_FORCE() ((void)0)
#define EL_DEBUG_TASK_BEGIN(task) ((void)0)
#define EL_DEBUG_TASK_END(task) ((void)0)
#define EL_DEBUG_PROBE(kind, a, b) ((void)0)
#define EL_DEBUG_PROBE_ACTOR(actor) ((void)0)

#endif /* EL_DEBUG_SERVER */

#endif /* EL_DEBUG_H */
