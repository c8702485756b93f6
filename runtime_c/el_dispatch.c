/* EasyLab runtime: the LET dispatcher (see el_dispatch.h). */
#include "el_dispatch.h"
#include "el_model.h"
#include "el_port.h"
#include "el_debug.h" /* the debugger's hooks: empty macros without a debug server */
#ifdef EL_THREADS
#include "el_threads.h" /* a multi-core build: el_gen_bodies runs the bodies (docs/multicore.md) */
#endif

static el_tick_t el_now;

el_tick_t el_now_tick(void)
{
    return el_now;
}

void el_idle(void)
{
    el_gen_interfaces_poll();
}

/* The task masks are walked by shifting them right (bit 0 is the task at
 * hand): no variable shifts, and a walk ends at the last task in the mask. */
EL_RUN_ATTRIBUTES void el_run(int argc, char **argv)
{
    el_tick_t base = 0u;
    el_task_mask_t pending = 0u; /* released, not yet published */
    uint16_t i;
    uint8_t task;

    if (!el_port_init(argc, argv)) {
        return;
    }
    el_gen_boot();
    el_gen_interfaces_boot();
    for (;;) {
        for (i = 0u; i < el_instant_count; i++) {
            el_task_mask_t publish, release, mask;
            el_now = (el_tick_t)(base + EL_ROM_READ_WTICK(&el_instants[i].tick));
            if (!el_port_wait_tick((el_wtick_t)el_now)) {
                el_gen_shutdown();
                el_port_shutdown();
                return;
            }
            /* Outputs due now become visible before the inputs of tasks
             * released now are read. */
            publish = (el_task_mask_t)(EL_ROM_READ_MASK(&el_instants[i].publish) & pending);
            pending &= (el_task_mask_t)~publish;
            for (task = 0u; publish != 0u; task++, publish = (el_task_mask_t)(publish >> 1)) {
                if ((publish & 1u) != 0u) {
                    el_gen_publish(task);
                }
            }
            el_port_inputs(el_now);
            EL_DEBUG_INSTANT(); /* queued debugger writes; halts at an instant */
            release = EL_ROM_READ_MASK(&el_instants[i].release);
            if (release != 0u) {
                el_gen_read_devices(release);
            }
            EL_DEBUG_FORCE(); /* forced values over what was read; conditional breakpoints */
            for (task = 0u, mask = release; mask != 0u; task++, mask = (el_task_mask_t)(mask >> 1)) {
                if ((mask & 1u) != 0u) {
                    el_gen_release(task);
                }
            }
            el_port_instant(el_now);
            pending |= release;
#ifdef EL_THREADS
            el_gen_bodies(release);
#endif
            for (task = 0u; release != 0u; task++, release = (el_task_mask_t)(release >> 1)) {
                if ((release & 1u) != 0u) {
                    el_wtick_t late;
                    EL_DEBUG_TASK_BEGIN(task); /* task breakpoints, step by task */
#ifndef EL_THREADS
                    el_gen_body(task);
#endif
                    EL_DEBUG_TASK_END(task);
                    /* Lateness never changes the published values; it is
                     * counted so that it is never silent. */
                    late = (el_wtick_t)(el_port_real_tick() - (el_wtick_t)el_now);
                    if (late > EL_ROM_READ_WTICK(&el_task_deadline_ticks[task]) && el_overruns[task] < UINT16_MAX) {
                        el_overruns[task]++;
                    }
                }
            }
        }
        base = (el_tick_t)(base + el_hyperperiod_ticks);
    }
}
