/* EasyLab simulator harnesses: the chips of one build on the simulated
 * buses (the chip-model API is el_chip.h; this is the harness's side).
 *
 * The build's table (sim_model.c, generated) names one entry per chip: the
 * std chips and the chip files a model brings (`sim "x_chip.c"`), each at
 * the bus address, chip select, UART or pins its device claims. A board's
 * harness turns what its simulator sees on the MCU's buses into calls of
 * the functions below (the AVR's from simavr's TWI and SPI messages, the
 * PIC18's from gpsim's MSSP registers), the same for every board:
 *
 * - I2C: sim_chips_i2c_start at each START (and repeated START) with the
 *   address byte; the chip at that address (if any, and if it acknowledges)
 *   takes the bytes written and gives the bytes read until the STOP. An
 *   address nobody acknowledges is a NACK the firmware sees.
 * - SPI: sim_chips_spi_select when a chip select pin changes level;
 *   sim_chips_spi_byte for each byte the master clocks: the selected
 *   chip's answer, or 0xFF (an idle MISO, pulled up) when no chip is
 *   selected or the selected one has no model.
 * - UART: sim_chips_uart_byte for each byte the MCU sends on a UART (when
 *   the firmware hands it to the transmitter): the chips on that UART take
 *   it. A chip's el_chip_uart_send reaches sim_board_uart_receive for its
 *   own UART only; the harness puts the byte on the MCU's RX line, where
 *   its reception ends one character time later (after the byte before
 *   it), and drops it while the receiver is off, as a board would.
 * - Pins: sim_chips_pin_driven for each pin a chip's device claims
 *   (sim_chip_entry_t.pins) whenever a write of the firmware may have
 *   changed the level it drives the pin to (the pin an output); the chip
 *   claiming it sees the changes only (pin_edge), the first level the
 *   firmware drives included. A chip's el_chip_pin_drive reaches
 *   sim_board_pin_drive for its device's pins only: the firmware reads the
 *   level at once.
 * A chip sending on a UART or driving a pin its device does not claim is
 * an error naming it (el_chip_error), which ends the run (sim_stop) with
 * exit status SIM_EXIT_RUN.
 */
#ifndef SIM_CHIPS_H
#define SIM_CHIPS_H

#include "el_chip.h"

#include <stdbool.h>
#include <stdint.h>

enum { SIM_CHIP_I2C = 1, SIM_CHIP_SPI = 2, SIM_CHIP_UART = 3, SIM_CHIP_PINS = 4 };

/* One chip of the build (sim_model.c). */
typedef struct {
    const el_chip_ops_t *ops;
    uint8_t kind;                   /* SIM_CHIP_... */
    uint8_t bus;                    /* i2c[bus], spi[bus], the UART */
    uint8_t address;                /* I2C */
    uint16_t cs;                    /* SPI: the chip select (the board's pin numbering) */
    const char *cs_name;            /* SPI: "PB2" */
    const char *device;             /* the device's path */
    uint8_t value_count;            /* the device's `out` data */
    const char *const *value_names;
    uint8_t param_count;            /* the device's integer parameters (el_chip_param) */
    const char *const *param_names;
    const int64_t *param_values;
    uint8_t pin_count;              /* the pins the device claims (`claims pin["PD5"]`) */
    const uint16_t *pins;           /* their numbers (the board's numbering, as cs) */
} sim_chip_entry_t;

extern const sim_chip_entry_t sim_chip_table[];
extern const uint16_t sim_chip_table_count;

/* Give every chip its zeroed state and call its reset; `dir` is --chips
 * (NULL: memories erased each run). False after a message. */
bool sim_chips_start(const char *dir);
/* Call every chip's finish and save the memories (--chips). False after a
 * message, or when a chip reported an error during the run. */
bool sim_chips_finish(void);

/* The stimulus set value `k` of chip `index` (the build's table names the
 * stimulus columns that reach a chip). False after the chip's message. */
bool sim_chips_value(uint16_t index, uint8_t k, const el_chip_value_t *value);

bool sim_chips_i2c_start(uint8_t bus, uint8_t address, bool read); /* acknowledged? */
bool sim_chips_i2c_write(uint8_t bus, uint8_t byte);               /* acknowledged? */
uint8_t sim_chips_i2c_read(uint8_t bus);
void sim_chips_i2c_stop(uint8_t bus);

void sim_chips_spi_select(uint8_t bus, uint16_t cs, bool selected);
uint8_t sim_chips_spi_byte(uint8_t bus, uint8_t mosi);

void sim_chips_uart_byte(uint8_t uart, uint8_t byte);
/* The firmware drives `pin` (one of a chip's pins) to `level`: the chip
 * claiming it sees a pin_edge when the level changed. */
void sim_chips_pin_driven(uint16_t pin, bool level);

/* ---- what a board's harness provides the chips ---- */

/* The simulated time in microseconds. */
uint64_t sim_board_now_us(void);
/* A byte into the MCU's UART `uart` (as if on its RX line): its reception
 * ends one character time (at the baud rate the firmware set) after the
 * byte before it or, on an idle line, after now. */
void sim_board_uart_receive(uint8_t uart, uint8_t byte);
/* Drive an input pin of the MCU: the firmware reads `level` from now on. */
void sim_board_pin_drive(uint16_t pin, bool level);

#endif /* SIM_CHIPS_H */
