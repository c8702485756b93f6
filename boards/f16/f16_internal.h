/* EasyLab f16 board: what the port's files share (generated code includes
 * el_board.h, never this).
 *
 * The port is in two layers. f16_port.c is the port interface of
 * runtime_c/el_port.h over a small hardware layer; it is the same C on the
 * MB90F543 and on the 16-bit proxy. The hardware layer is f16_hw.c on the
 * MB90F543 (reload timer 0 for the tick, the CPU's interrupt flag) and
 * proxy/f16p_hw.c on the 8051 that the proxy runs in s51 (its Timer 0 and
 * EA), so that the proxy's runs exercise the port's own tick, wait and
 * critical-section logic with a 16-bit int.
 *
 * el_f16_config.h is generated per build (the tick timer's period and
 * interrupts per tick, the clock, the UARTs, the vectors).
 */
#ifndef F16_INTERNAL_H
#define F16_INTERNAL_H

#include "el_types.h"
#include "el_port.h"
#include "el_f16_config.h"

/* ---- the hardware layer (f16_hw.c, proxy/f16p_hw.c) ---- */

/* Clocks and what the port owns, before anything else. */
void el_f16_hw_init(void);
/* The tick timer: an interrupt every EL_F16_TICK_PERIOD fine-clock units,
 * its handler runs EL_F16_TICK_ISR_BODY(); restart begins a fresh period now. */
void el_f16_tick_timer_start(void);
void el_f16_tick_timer_restart(void);
/* Fine-clock units of the current period so far, and whether a period
 * ended whose interrupt has not been served (interrupts masked). */
uint16_t el_f16_tick_timer_elapsed(void);
bool el_f16_tick_timer_pending(void);
/* The CPU's interrupt flag: save (then off), restore, on. */
el_irq_state_t el_f16_hw_irq_save(void);
void el_f16_hw_irq_restore(el_irq_state_t state);
void el_f16_hw_irq_on(void);
/* Whether the run goes on at this tick (the proxy's simulations end at
 * --duration; a part runs for ever). */
bool el_f16_hw_run_on(uint32_t tick);
/* The instant's two hooks (el_port_inputs, el_port_instant): the proxy's
 * simulations apply the stimulus and record the trace there. */
void el_f16_hw_inputs(el_tick_t tick);
void el_f16_hw_instant(el_tick_t tick);
/* Non-volatile storage (the MB90F543 has none: the build refuses persist). */
bool el_f16_hw_nv_read(uint16_t offset, void *data, uint16_t size);
bool el_f16_hw_nv_write(uint16_t offset, const void *data, uint16_t size);
/* The run is over (the proxy stops the simulator; a part stays stopped). */
void el_f16_hw_shutdown(void);

/* UART1 for the debug interface or a proxy's link (f16_uart.c;
 * el_f16_hw_init opens it). */
void el_f16_debug_open(void);
void el_f16_remote_open(void);
/* A software reset (LPMCR's RST): the part starts again from its reset vector. */
void el_f16_hw_reset(void);
/* The devices' interrupt levels (generated el_f16_devices.c). */
void el_f16_devices_boot(void);

/* ---- the port (f16_port.c) ---- */

/* The tick's count, which the tick timer's interrupt handler advances with
 * EL_F16_TICK_ISR_BODY (a macro, not a call: a handler that calls a
 * function saves every register on the stack, and the proxy's 8051 has a
 * small one). Additions only, here and in el_f16_clock: a 32-bit
 * multiplication or division is a library call on a 16-bit CPU. */
typedef struct {
    volatile uint32_t ticks;     /* LET ticks since el_port_init */
    volatile uint32_t fine_base; /* the fine clock when the current timer period began */
    volatile uint16_t isr_left;  /* interrupts left in this tick */
} el_f16_tick_state_t;
extern el_f16_tick_state_t el_f16_tick_state;

#define EL_F16_TICK_ISR_BODY()                                     \
    do {                                                           \
        el_f16_tick_state.fine_base += EL_F16_TICK_PERIOD;         \
        if (--el_f16_tick_state.isr_left == 0u) {                  \
            el_f16_tick_state.isr_left = EL_F16_TICK_ISRS;         \
            el_f16_tick_state.ticks++;                             \
        }                                                          \
    } while (0)
/* The fine clock: EL_F16_CLOCK_KHZ units per ms (rounded up), since
 * el_port_init; wraps at 2^32. */
uint32_t el_f16_clock(void);
uint32_t el_f16_clock_from_us(uint32_t us);

#endif /* F16_INTERNAL_H */
