/* EasyLab: the chip-model API of the simulator harnesses (docs/boards.md,
 * "Chip models").
 *
 * A chip model is a C file that plays a chip on a simulated board: it
 * answers the firmware's own drivers byte by byte on an I2C or SPI bus,
 * takes and gives bytes on a UART, sees and drives pins, and takes the
 * chip's physical values (a temperature, a voltage) from the stimulus
 * columns of its device's `out` data. A model brings one for a device type
 * next to its handlers:
 *
 *     driver "mcp3201" impl avr "mcp3201_avr.c" sim "mcp3201_chip.c"
 *
 * and every simulator harness (the AVR's on simavr, the PIC18's on gpsim)
 * runs it for each device of that type, at the bus address or chip select
 * the device claims. The std chips (the TMP102-class sensor, the I2C and
 * SPI EEPROMs) are chip models on this same API (sim/chips/).
 *
 * The file defines one descriptor under the name EL_CHIP (the build
 * defines it per file, so two chip files never collide):
 *
 *     #include "el_chip.h"
 *
 *     typedef struct { uint16_t count; uint8_t k; } mcp3201_t;
 *
 *     static void on_select(el_chip_t *chip, bool selected) { ... }
 *     static uint8_t on_byte(el_chip_t *chip, uint8_t mosi) { ... }
 *
 *     const el_chip_ops_t EL_CHIP = {
 *         .name = "mcp3201", .state_size = sizeof(mcp3201_t),
 *         .spi_select = on_select, .spi_byte = on_byte,
 *     };
 *
 * Every callback is optional (NULL: the chip ignores the event, answers
 * 0xFF, acknowledges nothing). They run inside the simulator, between two
 * of the MCU's instructions: no blocking, no sleeping; the chip's time is
 * el_chip_now_us(). The harness zeroes a chip's state before `reset`.
 */
#ifndef EL_CHIP_H
#define EL_CHIP_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* The value of a stimulus column: integer data in `i`, float data in `f`
 * (`is_float`), as the stimulus gives it for the device's `out` datum. */
typedef struct {
    bool is_float;
    int64_t i;
    double f;
} el_chip_value_t;

/* One chip on the simulated board: what the harness knows of it. */
typedef struct el_chip {
    void *state;              /* the model's own, state_size bytes, zeroed at start */
    const char *device;       /* the device's path in the model ("adc") */
    uint8_t bus;              /* i2c[bus] or spi[bus] */
    uint8_t address;          /* I2C: the 7-bit address the device claims */
    uint16_t cs;              /* SPI: the chip select's pin (the board's numbering) */
    const char *cs_name;      /* SPI: its name ("PB2") */
    uint8_t value_count;      /* the device's `out` data, in declaration order */
    const char *const *value_names; /* their names ("value") */
    void *harness;            /* the harness's own */
    uint8_t pin_count;        /* the pins the device claims (`claims pin[...]`), */
    const uint16_t *pins;     /* in the order of its claims (the board's numbering) */
} el_chip_t;

typedef struct {
    const char *name;         /* for messages: "mcp3201" */
    size_t state_size;
    /* After the state is zeroed, before the MCU's first instruction. */
    void (*reset)(el_chip_t *chip);
    /* The stimulus value of the device's `out` datum `k` (a stimulus
     * column; value_names[k]), at each instant the stimulus is applied;
     * false (after el_chip_error) for a value the chip cannot have: the run
     * ends with that message. */
    bool (*value)(el_chip_t *chip, uint8_t k, const el_chip_value_t *value);

    /* I2C, at the chip's address only. `start`: its address with R/W (a
     * repeated START too), true to acknowledge it. `write`: a byte the
     * master wrote, true to acknowledge it. `read`: the byte the master
     * reads next. `stop`: the STOP that ends the transaction. */
    bool (*i2c_start)(el_chip_t *chip, bool read);
    bool (*i2c_write)(el_chip_t *chip, uint8_t byte);
    uint8_t (*i2c_read)(el_chip_t *chip);
    void (*i2c_stop)(el_chip_t *chip);

    /* SPI: the chip select fell (true) or rose (false); while selected,
     * each byte the master clocks out comes to spi_byte, which returns the
     * byte the chip shifted out meanwhile. */
    void (*spi_select)(el_chip_t *chip, bool selected);
    uint8_t (*spi_byte)(el_chip_t *chip, uint8_t mosi);

    /* UART (a device claiming a UART): a byte the MCU sent, when the
     * firmware hands it to the transmitter. */
    void (*uart_byte)(el_chip_t *chip, uint8_t byte);

    /* A pin the device claims (one of pins[]) changed level: the firmware
     * drove it, an output, to `level` (the first level it drives too). */
    void (*pin_edge)(el_chip_t *chip, uint16_t pin, bool level);

    /* The run ends: write back what must outlive it (el_chip_memory keeps
     * itself). */
    void (*finish)(el_chip_t *chip);
} el_chip_ops_t;

/* ---- what the harness offers a chip ---- */

/* The simulated time, in microseconds since the MCU's reset. */
uint64_t el_chip_now_us(const el_chip_t *chip);

/* A byte the chip sends to the MCU on its device's UART: the MCU has it
 * one character time later (after the bytes sent before it), at the baud
 * rate the firmware set; lost while its receiver is off. An error on a
 * device claiming no UART. */
void el_chip_uart_send(el_chip_t *chip, uint8_t byte);

/* Drive a pin the device claims (an input of the MCU; one of pins[]) to
 * `level`: the firmware reads it at once. An error on any other pin. */
void el_chip_pin_drive(el_chip_t *chip, uint16_t pin, bool level);

/* The device's integer (or bool) parameter `name` as the model gives it
 * (`bytes` of an EEPROM log); `otherwise` when it has none of that name. */
int64_t el_chip_param(const el_chip_t *chip, const char *name, int64_t otherwise);

/* `size` bytes of memory that outlive the run: with --chips DIR they are
 * loaded from and saved to DIR/<device>.bin, otherwise 0xFF (erased) each
 * run. The same pointer on every call (one memory per chip); NULL (after a
 * message) when it cannot be had. */
uint8_t *el_chip_memory(el_chip_t *chip, size_t size);

/* Report a problem of the chip (printf-style), prefixed with the device's
 * path: "adc (chip model): ...". */
void el_chip_error(const el_chip_t *chip, const char *format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

#endif /* EL_CHIP_H */
