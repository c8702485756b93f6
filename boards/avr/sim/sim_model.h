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

/* A chip on a bus (avr_chips.h): one per address a device claims on an
 * I2C bus where a chip of a kind the harness models answers, one per chip
 * select of a device whose chip it models on an SPI bus. */
enum { SIM_CHIP_TEMPERATURE = 1, SIM_CHIP_EEPROM = 2, SIM_CHIP_SPI_EEPROM = 3 };

typedef struct {
    uint8_t bus;
    uint8_t address; /* I2C: its address; SPI: its chip select's bit */
    uint8_t kind;    /* SIM_CHIP_... */
    uint32_t bytes;  /* EEPROM: its memory (a power of two) */
    uint16_t page;   /* EEPROM: its page */
    char port;       /* SPI: its chip select's port ('B') */
} sim_chip_t;

extern const sim_chip_t sim_chips[];
extern const uint16_t sim_chip_count;
extern const sim_pin_t sim_pins[];
/* Bytes of the firmware's el_avr_sim_tick: 2 or 4 (el_types.h: el_tick_t). */
extern const uint8_t sim_tick_size;

#endif /* SIM_MODEL_H */
