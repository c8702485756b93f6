/* EasyLab f16 board: the hardware layer of the port on the MB90F543
 * (f16_internal.h; registers: mb90f543_regs.h).
 *
 * - Clock: the PLL multiplies the crystal by EL_F16_PLL_MULT (4 MHz x 4:
 *   a 16 MHz machine clock), chosen at boot.
 * - Tick: reload timer 0 counts the machine clock / EL_F16_TICK_DIVIDER
 *   down from EL_F16_TICK_RELOAD and interrupts at each underflow (vector
 *   EL_F16_TICK_VECTOR): one fine-clock unit is one count.
 * - Interrupts: fcc907s has intrinsics that set and clear the CPU's I flag
 *   but none that reads it, so the port keeps the flag's state as it last
 *   set it (interrupt handlers return with the flag they found).
 * - The MB90F543 has no EEPROM, and its flash cannot be written while the
 *   program runs from it: no non-volatile storage (the backend refuses
 *   `persist` for this part).
 * - Between ticks the CPU polls (el_idle); the low-power modes are not used.
 */
#include "f16_internal.h"
#include "f16_compiler.h"
#include "mb90f543_regs.h"

#if defined(EL_DEBUG) && EL_DEBUG && !(defined(EL_RELEASE) && EL_RELEASE)
#include "el_debug.h" /* EL_DEBUG_SERVER: whether to open the debug UART */
#endif

static volatile bool irq_on; /* the I flag as the port last set it */

void el_f16_hw_init(void)
{
    /* Multiplier first, then switch the machine clock to the PLL and wait
     * until it runs from it. */
    EL_F16_CKSCR = (uint8_t)((EL_F16_CKSCR & (uint8_t)~EL_F16_CKSCR_CS_MASK) | (uint8_t)(EL_F16_PLL_MULT - 1u));
    EL_F16_CKSCR = (uint8_t)(EL_F16_CKSCR & (uint8_t)~EL_F16_CKSCR_MCS);
    while ((EL_F16_CKSCR & EL_F16_CKSCR_MCM) != 0u) {
    }
    EL_F16_SET_ILM(7u); /* interrupts of every level (ICR levels 0..6) may come */
    el_f16_devices_boot();
#if defined(EL_F16_DEBUG_UART) && defined(EL_DEBUG_SERVER) && EL_DEBUG_SERVER
    el_f16_debug_open();
#endif
#if defined(EL_F16_REMOTE_UART) && defined(EL_REMOTE_PROXY) && EL_REMOTE_PROXY
    el_f16_remote_open(); /* the proxy's link */
#endif
}

void el_f16_hw_reset(void)
{
    /* RST = 0 starts an internal reset; TMD stays 1 (0 would enter the
     * watch mode) and the CPU runs without intermittent cycles (CG = 00). */
    EL_F16_LPMCR = EL_F16_LPMCR_TMD;
    for (;;) {
    }
}

void el_f16_tick_timer_start(void)
{
    EL_F16_TMCSR0 = 0u;
    EL_F16_TMRLR0 = (uint16_t)EL_F16_TICK_RELOAD;
    EL_F16_ICR(EL_F16_ICR_OF_VECTOR(EL_F16_TICK_VECTOR)) = EL_F16_TICK_LEVEL;
    EL_F16_TMCSR0 = (uint16_t)((uint16_t)EL_F16_TICK_CSL << EL_F16_TMCSR_CSL_SHIFT) | EL_F16_TMCSR_RELD |
                    EL_F16_TMCSR_INTE | EL_F16_TMCSR_CNTE | EL_F16_TMCSR_TRG;
}

void el_f16_tick_timer_restart(void)
{
    /* A software trigger reloads the counter: a full period from now. */
    EL_F16_TMCSR0 = (uint16_t)((EL_F16_TMCSR0 & (uint16_t)~EL_F16_TMCSR_UF) | EL_F16_TMCSR_TRG);
}

uint16_t el_f16_tick_timer_elapsed(void)
{
    /* The counter runs from the reload value down to 0. */
    return (uint16_t)(EL_F16_TICK_RELOAD - EL_F16_TMR0);
}

bool el_f16_tick_timer_pending(void)
{
    return (EL_F16_TMCSR0 & EL_F16_TMCSR_UF) != 0u;
}

EL_F16_ISR(el_f16_tick_interrupt)
{
    EL_F16_TMCSR0 = (uint16_t)(EL_F16_TMCSR0 & (uint16_t)~(EL_F16_TMCSR_UF | EL_F16_TMCSR_TRG));
    EL_F16_TICK_ISR_BODY();
}

el_irq_state_t el_f16_hw_irq_save(void)
{
    el_irq_state_t state = irq_on ? 1u : 0u;
    EL_F16_DISABLE_IRQ();
    irq_on = false;
    return state;
}

void el_f16_hw_irq_restore(el_irq_state_t state)
{
    if (state != 0u) {
        irq_on = true;
        EL_F16_ENABLE_IRQ();
    } else {
        EL_F16_DISABLE_IRQ();
        irq_on = false;
    }
}

void el_f16_hw_irq_on(void)
{
    irq_on = true;
    EL_F16_ENABLE_IRQ();
}

bool el_f16_hw_run_on(uint32_t tick)
{
    (void)tick;
    return true;
}

void el_f16_hw_inputs(el_tick_t tick)
{
    (void)tick;
}

void el_f16_hw_instant(el_tick_t tick)
{
    (void)tick;
}

bool el_f16_hw_nv_read(uint16_t offset, void *data, uint16_t size)
{
    (void)offset;
    (void)data;
    return size == 0u;
}

bool el_f16_hw_nv_write(uint16_t offset, const void *data, uint16_t size)
{
    (void)offset;
    (void)data;
    return size == 0u;
}

void el_f16_hw_shutdown(void)
{
    EL_F16_DISABLE_IRQ();
    irq_on = false;
    for (;;) {
    }
}
