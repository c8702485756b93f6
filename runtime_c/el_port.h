/* EasyLab runtime: the port interface every board implements.
 *
 * A board provides these functions (in boards/<board>/) and nothing else is
 * board-specific in the runtime. Logical time counts ticks of the model's
 * base period (EL_TICK_US microseconds, generated); tick counters wrap at
 * 2^32, or 2^16 in a narrow-tick build (el_types.h: el_wtick_t), and are
 * compared wrap-safely.
 */
#ifndef EL_PORT_H
#define EL_PORT_H

#include "el_types.h"

/* Start the clock, UARTs and whatever the board needs; called once at boot
 * before any device is opened. argc/argv are the host board's command line
 * (boards without one pass 0 and a null pointer). Returns false to stop. */
bool el_port_init(int argc, char **argv);

/* Block until logical tick `tick` has come (real-time boards), or return at
 * once (virtual time). Returns false when the board wants the run to end
 * (host: --duration reached). */
bool el_port_wait_tick(el_wtick_t tick);

#if defined(EL_ROUND_SLAVE)
/* A slave of a Modbus round (docs/distribution.md; the node's generated
 * el_link.c defines it): its ticks follow the master's sync, not its timer,
 * so its el_port_wait_tick asks this first (a round keeps 32-bit ticks:
 * el_types.h). 1: the tick may run now; 0: wait for the sync. */
int8_t el_round_gate(uint32_t tick);
#endif

/* Serve the interfaces for at most `max_ms` milliseconds (less if something
 * arrives): the wait of a program halted by its debugger, while logical
 * time stands still. */
void el_port_idle(uint16_t max_ms);

/* Let real time resume from the current tick (after a halt), instead of
 * catching up with the ticks missed meanwhile. */
void el_port_resync(void);

/* The real-time tick counter, for lateness (overrun) accounting. In virtual
 * time it is the logical tick being processed. */
el_wtick_t el_port_real_tick(void);

/* Critical sections around data shared with interrupts. Nestable through
 * the saved state. */
typedef uint8_t el_irq_state_t;
el_irq_state_t el_port_irq_save(void);
void el_port_irq_restore(el_irq_state_t state);

/* Called by the dispatcher once per logical instant, after the outputs due
 * then are published and before devices are read and inputs latched: where
 * writes from outside (debug and service interfaces, the host board's
 * stimulus for params and vars) take effect. */
void el_port_inputs(el_tick_t tick);

/* Called by the dispatcher once per logical instant, after publication,
 * interface writes and device reads: the host board records its trace
 * here. `tick` is the absolute logical tick (el_types.h: el_tick_t). */
void el_port_instant(el_tick_t tick);

/* Non-volatile storage for `persist` params: `size` bytes at `offset`.
 * Return false on failure (reported by the caller). */
bool el_port_nv_read(uint16_t offset, void *data, uint16_t size);
bool el_port_nv_write(uint16_t offset, const void *data, uint16_t size);

/* A node with DDS exports (docs/distribution.md, "DDS") calls this when
 * export `index` has a value: at a publication of its var's writer, or a
 * release of its channel's consumer (the tokens it takes); `values` holds
 * the export's values. Only a board whose nodes may be DDS peers defines
 * it, and only a program with exports calls it. */
void el_port_export(uint8_t index, const void *values);

/* Called once when the run ends (host: --duration); MCU ports never return. */
void el_port_shutdown(void);

#endif /* EL_PORT_H */
