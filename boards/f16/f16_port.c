/* EasyLab f16 board: the port interface of runtime_c/el_port.h, over the
 * hardware layer of f16_internal.h (the same C on the MB90F543 and on the
 * 16-bit proxy).
 *
 * Time: the tick timer interrupts every EL_F16_TICK_PERIOD fine-clock units
 * and every EL_F16_TICK_ISRS interrupts make one LET tick of el_tick_us
 * (the backend chose both so that their product is the tick, exactly when
 * it can: docs/boards.md, "The F16 board"). Tick n is due n ticks after
 * el_port_init. el_port_wait_tick serves the interfaces (el_idle) until the
 * tick has come; a late tick returns at once (the dispatcher counts the
 * lateness, nothing is skipped).
 *
 * Critical sections save the CPU's interrupt flag and clear it; restoring
 * puts back what they found, so they nest.
 */
#include "f16_internal.h"
#include "el_dispatch.h"

el_f16_tick_state_t el_f16_tick_state;

uint32_t el_f16_clock(void)
{
    el_irq_state_t state = el_f16_hw_irq_save();
    uint32_t base = el_f16_tick_state.fine_base;
    uint16_t elapsed = el_f16_tick_timer_elapsed();
    if (el_f16_tick_timer_pending()) { /* a period ended unserved: it counts */
        base += EL_F16_TICK_PERIOD;
        elapsed = el_f16_tick_timer_elapsed();
    }
    el_f16_hw_irq_restore(state);
    return base + elapsed;
}

uint32_t el_f16_clock_from_us(uint32_t us)
{
    /* Whole milliseconds, then the rest rounded up: 32-bit arithmetic only. */
    uint32_t ms = us / 1000u;
    uint32_t rest = us - ms * 1000u;
    return ms * (uint32_t)EL_F16_CLOCK_KHZ + (rest * (uint32_t)EL_F16_CLOCK_KHZ + 999u) / 1000u;
}

static uint32_t read_ticks(void)
{
    el_irq_state_t state = el_f16_hw_irq_save();
    uint32_t t = el_f16_tick_state.ticks;
    el_f16_hw_irq_restore(state);
    return t;
}

bool el_port_init(int argc, char **argv)
{
    (void)argc;
    (void)argv;
    el_f16_hw_init();
    el_f16_tick_state.ticks = 0u;
    el_f16_tick_state.fine_base = 0u;
    el_f16_tick_state.isr_left = EL_F16_TICK_ISRS;
    el_f16_tick_timer_start();
    el_f16_hw_irq_on();
    return true;
}

bool el_port_wait_tick(uint32_t tick)
{
    if (!el_f16_hw_run_on(tick)) {
        return false;
    }
    while ((int32_t)(read_ticks() - tick) < 0) {
        el_idle();
    }
    return true;
}

void el_port_idle(uint16_t max_ms)
{
    uint32_t span = (uint32_t)max_ms * EL_F16_CLOCK_KHZ; /* before the clock starts: it takes time */
    uint32_t start = el_f16_clock();
    do {
        el_idle();
    } while (el_f16_clock() - start < span);
}

void el_port_resync(void)
{
    el_irq_state_t state = el_f16_hw_irq_save();
    /* The current tick is due now: a fresh tick period starts. */
    el_f16_tick_state.ticks = (uint32_t)el_now_tick();
    el_f16_tick_state.isr_left = EL_F16_TICK_ISRS;
    el_f16_tick_timer_restart();
    el_f16_hw_irq_restore(state);
}

uint32_t el_port_real_tick(void)
{
    return read_ticks();
}

el_irq_state_t el_port_irq_save(void)
{
    return el_f16_hw_irq_save();
}

void el_port_irq_restore(el_irq_state_t state)
{
    el_f16_hw_irq_restore(state);
}

void el_port_inputs(el_tick_t tick)
{
    el_f16_hw_inputs(tick);
}

void el_port_instant(el_tick_t tick)
{
    el_f16_hw_instant(tick);
}

bool el_port_nv_read(uint16_t offset, void *data, uint16_t size)
{
    return el_f16_hw_nv_read(offset, data, size);
}

bool el_port_nv_write(uint16_t offset, const void *data, uint16_t size)
{
    return el_f16_hw_nv_write(offset, data, size);
}

void el_port_shutdown(void)
{
    el_f16_hw_shutdown();
}

/* ---- the program (the proxy has its own: proxy/f16p_hw.c) ---- */

#if !defined(EL_F16_PROXY)
int main(void)
{
    el_run(0, (char **)0);
    el_port_shutdown();
    return 0;
}
#endif
