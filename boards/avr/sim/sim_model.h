/* EasyLab AVR board, simulator harness: what the generated sim_model.c of a
 * build tells the harness (the board's backend, simulator.py: sim_model_source).
 *
 * The el_model.h tables (el_items, el_charts, ...) describe the model as
 * in the firmware, but their addresses point at host-side mirrors: the
 * harness copies the values from the simulated MCU's RAM into them at each
 * instant and hands them to the host board's trace code (host_trace.c), so
 * that traces are the same files byte for byte. sim_item_addr gives each
 * item's address in the MCU's data space; sim_hw says how a device datum
 * reaches the hardware (an ADC channel, a pin, a UART, encoder pins): on
 * the AVR a pin is its port letter (a) and bit (b), an encoder's pins are
 * port letter << 8 | bit each. The tables every harness reads are declared
 * in sim/sim_harness.h; the pin table is the AVR's own.
 */
#ifndef SIM_MODEL_H
#define SIM_MODEL_H

#include "sim_chips.h"
#include "sim_harness.h"

/* A pin traced by --pins: a level, or a PWM output (its duty 0..255 from
 * the timer's compare register while the output is connected, else 0 or
 * 255 from the port bit). */
typedef struct {
    char port;         /* 'B' */
    uint8_t bit;
    uint8_t kind;      /* SIM_PIN_... */
    uint16_t ocr;      /* PWM: data address of OCRnx (low byte) */
    uint16_t tccra;    /* PWM: data address of TCCRnA */
    uint8_t com_bit;   /* PWM: COMnx1's bit in TCCRnA */
    const char *name;  /* "PB5" */
    const char *what;  /* the device */
} sim_pin_t;

extern const sim_pin_t sim_pins[];
/* Bytes of the firmware's el_avr_sim_tick: 2 or 4 (el_types.h: el_tick_t). */
extern const uint8_t sim_tick_size;

#endif /* SIM_MODEL_H */
