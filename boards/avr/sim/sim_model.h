/* EasyLab AVR board, simulator harness: what the generated sim_model.c of a
 * build tells the harness (the board's backend, simulator.py: sim_model_source).
 *
 * The el_model.h tables (el_items, el_charts, ...) describe the model as
 * in the firmware, but their addresses point at host-side mirrors: the
 * harness copies the values from the simulated MCU's RAM into them at each
 * instant and hands them to the host board's trace code (host_trace.c), so
 * that traces are the same files byte for byte. sim_item_addr gives each
 * item's address in the MCU's data space; sim_hw says how a device datum
 * reaches the hardware (an ADC channel, a pin, a UART, encoder pins).
 */
#ifndef SIM_MODEL_H
#define SIM_MODEL_H

#include "el_types.h"
#include "el_model.h"

typedef struct {
    uint16_t addr;  /* data-space address in the MCU (0xFFFF: not there) */
    uint16_t size;  /* bytes */
} sim_addr_t;

enum {
    SIM_HW_NONE = 0,
    SIM_HW_ADC,      /* a: channel; the value in ADC counts 0..1023 */
    SIM_HW_PIN_IN,   /* a: port letter, b: bit; the level the pin is driven to */
    SIM_HW_PIN_OUT,  /* a: port letter, b: bit (the firmware drives it) */
    SIM_HW_CAMERA,   /* a: UART; c: baud; line camera frames (drivers/el_drv_line_camera.h) */
    SIM_HW_ENCODER,  /* a, b: port letter << 8 | bit of pins A and B; quadrature edges */
    SIM_HW_PWM,      /* the firmware drives a PWM output */
    SIM_HW_I2C_TEMP  /* a: bus, b: address; the temperature of the sensor there, 1/16 degC (sim_chips.h) */
};

typedef struct {
    uint16_t item;   /* index into el_items */
    uint8_t kind;    /* SIM_HW_... */
    uint16_t a;
    uint16_t b;
    uint32_t c;
} sim_hw_t;

enum { SIM_PIN_LEVEL = 0, SIM_PIN_PWM = 1 };

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

/* A chip on a bus (sim_chips.h): one per address a device claims on an
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

extern const sim_addr_t sim_item_addr[];
extern const sim_addr_t sim_chart_addr[];
extern const uint16_t sim_tick_addr;
extern const sim_hw_t sim_hw[];
extern const uint16_t sim_hw_count;
extern const sim_pin_t sim_pins[];
extern const uint16_t sim_pin_count;
extern const char sim_uarts[];      /* the MCU's UARTs: "0" or "0123" */
extern const char sim_mcu[];        /* "atmega2560" */
extern const uint32_t sim_clock_hz;
extern const char sim_elf_default[];
extern const uint32_t sim_nv_size;

#endif /* SIM_MODEL_H */
