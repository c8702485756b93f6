/* EasyLab PIC18 board, simulator harness: what the generated sim_model.c of
 * a build tells the gpsim harness (the board's backend, simulator.py:
 * sim_model_source), beyond what every harness has (sim_harness.h).
 *
 * The el_model.h tables (el_items, el_charts, ...) describe the model as
 * in the firmware, but their addresses point at host-side mirrors: the
 * harness copies the values from the simulated MCU's RAM into them at each
 * instant and hands them to the host board's trace code, so that traces
 * are the same files byte for byte. Pins are the hardware layer's numbers
 * (port << 3 | bit: boards/pic18/pic18_hw.h).
 */
#ifndef SIM_MODEL_H
#define SIM_MODEL_H

#include "sim_harness.h"
#include "sim_chips.h" /* sim_chip_table: the chips on the MSSP's buses */

/* A pin traced by --pins: a level, or a PWM output (its duty 0..255 from
 * the CCP module's 10-bit compare value against Timer2's period). */
typedef struct {
    uint8_t pin;      /* port << 3 | bit */
    uint8_t kind;     /* SIM_PIN_... */
    uint8_t ccp;      /* PWM: CCP module 1 or 2 */
    const char *name; /* "RC2" */
    const char *what; /* the device */
} sim_pin_t;

extern const sim_pin_t sim_pins[];
extern const char sim_processor[];  /* gpsim's processor type: "p18f4520" */
extern const uint8_t sim_uart_parity; /* the EUSART's parity (a 9th bit): 0 none, 1 even, 2 odd */
/* RAM addresses of the firmware's simulation hooks (pic18_port.c) and of
 * el_pic18_kept (pic18_hw.c); 0xFFFF: absent. */
extern const uint16_t sim_mark_addr;
extern const uint16_t sim_busy_addr;
extern const uint16_t sim_kept_addr;
/* sdcc's software stack: its lowest byte and its size (el_pic18_stack.c). */
extern const uint16_t sim_stack_addr;
extern const uint16_t sim_stack_size;

#endif /* SIM_MODEL_H */
