/* EasyLab AVR board, simulator harness: simavr's TWI, SPI and pins to the chips'
 * dispatch (sim/sim_chips.h, shared by the harnesses), so that the
 * firmware's own drivers (the board's and those a model brings) run
 * against the chip models of the build (docs/boards.md, "Chip models"). */
#ifndef AVR_CHIPS_H
#define AVR_CHIPS_H

#include "sim_avr.h"

#include <stdbool.h>

/* Attach the chips of sim_chip_table to the MCU's TWI, SPI, the chip
 * select pins and the pins their devices claim (whether or not the build
 * has chips: an address nobody acknowledges is a NACK, a chip select
 * nobody answers reads 0xFF). */
bool avr_chips_attach(avr_t *avr); /* false after a message */

/* PORTx's data address (port 'B'); DDRx is the byte below, PINx below it. */
uint16_t avr_port_addr(char port);

#endif /* AVR_CHIPS_H */
