/* EasyLab runtime: the LET dispatcher and what generated code provides it.
 *
 * The dispatcher walks the generated table of instants over the
 * hyperperiod. At each instant: publish the outputs of the tasks whose
 * deadline it is (if they were released), read the devices of the tasks
 * released now (once per device), latch the released tasks' inputs, let
 * the board record the instant, then run the released tasks' bodies. The
 * bodies only touch task-local copies, so the order and speed of execution
 * never shows in the published values (docs/ir.md, "tasks").
 */
#ifndef EL_DISPATCH_H
#define EL_DISPATCH_H

#include "el_types.h"

/* A set of tasks, bit i for task i: 8, 16 or 32 bits, as many as the
 * program's tasks need where the board narrows it (EL_TASK_MASK_BITS, the
 * IR's `task_mask_bits`: docs/ir.md, "Dispatcher widths"), else 32. */
#if defined(EL_TASK_MASK_BITS) && EL_TASK_MASK_BITS == 8
typedef uint8_t el_task_mask_t;
#define EL_ROM_READ_MASK(p) EL_ROM_READ_U8(p)
#elif defined(EL_TASK_MASK_BITS) && EL_TASK_MASK_BITS == 16
typedef uint16_t el_task_mask_t;
#define EL_ROM_READ_MASK(p) EL_ROM_READ_U16(p)
#else
typedef uint32_t el_task_mask_t;
#define EL_ROM_READ_MASK(p) EL_ROM_READ_U32(p)
#endif

/* One entry of the dispatch table (generated, in ROM where possible). */
typedef struct {
    el_wtick_t tick;        /* within the hyperperiod */
    el_task_mask_t publish; /* tasks whose deadline it is (bit i = task i) */
    el_task_mask_t release; /* tasks released now */
} el_instant_t;

/* ---- provided by the generated model.c ---------------------------------- */
extern const el_instant_t el_instants[] EL_ROM;
extern const uint16_t el_instant_count;
extern const el_wtick_t el_task_deadline_ticks[] EL_ROM;
void el_gen_boot(void);                        /* open/start devices, actor start() */
void el_gen_shutdown(void);                    /* actor stop(), stop/close devices */
void el_gen_read_devices(el_task_mask_t released); /* read() of devices those tasks use */
void el_gen_release(uint8_t task);             /* latch inputs into the task's copy */
void el_gen_body(uint8_t task);                /* run the task's dataflows and charts */
void el_gen_publish(uint8_t task);             /* outputs, channels, device write() */
void el_gen_interfaces_boot(void);             /* start the debug and service interfaces */
void el_gen_interfaces_poll(void);             /* serve them (from el_idle) */

/* ---- provided by the runtime --------------------------------------------- */

/* Boot, then dispatch until the board's el_port_wait_tick says stop.
 * EL_RUN_ATTRIBUTES: what a board adds to it (board.toml's cflags; the AVR
 * board's main keeps nothing across the call, so el_run need not save the
 * caller's registers: OS_task). */
#ifndef EL_RUN_ATTRIBUTES
#define EL_RUN_ATTRIBUTES
#endif
EL_RUN_ATTRIBUTES void el_run(int argc, char **argv);

/* Serve the interfaces: ports call it while they wait between instants
 * (MCU ports in their wait loop; the host board after serving its
 * descriptors). */
void el_idle(void);

/* The absolute logical tick of the instant being processed. */
el_tick_t el_now_tick(void);

/* Copy n elements (any type) from src to dst. */
#define EL_COPY(dst, src, n) \
    do { uint16_t el_copy_i_; for (el_copy_i_ = 0u; el_copy_i_ < (uint16_t)(n); el_copy_i_++) \
        { (dst)[el_copy_i_] = (src)[el_copy_i_]; } } while (0)

/* Circular SDF buffers (non-single-appearance schedules): take or put n
 * tokens at index idx of a ring of `size`, wrapping. */
#define EL_RING_GET(ring, idx, size, dst, n) \
    do { uint16_t el_ring_i_; for (el_ring_i_ = 0u; el_ring_i_ < (uint16_t)(n); el_ring_i_++) { \
        (dst)[el_ring_i_] = (ring)[(idx)]; (idx) = (uint16_t)((idx) + 1u == (size) ? 0u : (idx) + 1u); } } while (0)
#define EL_RING_PUT(ring, idx, size, src, n) \
    do { uint16_t el_ring_i_; for (el_ring_i_ = 0u; el_ring_i_ < (uint16_t)(n); el_ring_i_++) { \
        (ring)[(idx)] = (src)[el_ring_i_]; (idx) = (uint16_t)((idx) + 1u == (size) ? 0u : (idx) + 1u); } } while (0)

#endif /* EL_DISPATCH_H */
