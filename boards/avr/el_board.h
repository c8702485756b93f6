/* EasyLab AVR board: what generated code sees of it.
 *
 * Device code calls el_drv_<driver>_<handler>(&el_dev<id>) (open, start,
 * read, write, stop, close). el_avr_devices.h, generated for each build,
 * defines each device el_dev<id> as a `static const` description (its
 * registers, bits, channel and the addresses of its data) and includes the
 * drivers' headers (drivers/), whose handlers are static inline: with the
 * description constant, avr-gcc reduces a DigitalOut write to SBI/CBI.
 * Drivers that need interrupt handlers or state (encoder, line camera)
 * get them in the generated el_avr_devices.c.
 */
#ifndef EL_BOARD_H
#define EL_BOARD_H

#include "el_types.h"

#define EL_BOARD_AVR 1
#define EL_BOARD_NAME "avr"

/* The runtime's entry point (runtime_c/el_dispatch.c); main() calls it. */
void el_run(int argc, char **argv);

/* A pin, as the buses take a chip select (runtime_c/el_bus.h: el_pin_t):
 * its PINx register (DDRx and PORTx follow it) and its bit. */
struct el_pin {
    volatile uint8_t *pin;
    uint8_t mask;
};

#include "el_avr_devices.h" /* generated: el_dev<id> and the drivers */

#endif /* EL_BOARD_H */
