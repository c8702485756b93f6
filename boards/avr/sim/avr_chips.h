/* EasyLab AVR board, simulator harness: models of the chips on the I2C and
 * SPI buses (docs/boards.md, "Simulation"), answering the TWI and the SPI of
 * simavr the way the chips answer on a board, so that the firmware's own
 * drivers (the board's and those a model brings) run against them:
 *
 * - an LM75 / TMP102-class temperature sensor at each address 0x48..0x4F a
 *   device claims: registers temperature (0), configuration (1), T_LOW (2)
 *   and T_HIGH (3) behind a pointer register, each read most significant
 *   byte first. Its temperature is the stimulus value of the claiming
 *   device's first `out` datum, in 1/16 degC (the TMP102's 12-bit count;
 *   -55 .. +150 degC): the register holds it left-justified, or in the
 *   TMP102's 13-bit extended mode when the configuration's EM bit is set.
 *   The register follows the stimulus at once (a TMP102 converts 4 times a
 *   second).
 * - a 24LC256-class EEPROM at each address 0x50..0x57 a device claims: a
 *   two-byte address, sequential reads across the whole memory, page writes
 *   that wrap inside their page, a write cycle of 5 ms after the STOP during
 *   which the chip acknowledges nothing (so drivers poll it). Erased bytes
 *   are 0xFF; --chips DIR keeps each memory in DIR/i2c<bus>-0x<addr>.bin.
 *
 * - a 25LC256-class SPI EEPROM behind the chip select of each std
 *   SpiEepromLog (driver spi_eeprom_log): READ, WRITE (after WREN; page
 *   writes wrap inside their page), RDSR (WIP, WEL), WREN, WRDI, in SPI
 *   mode 0; a write cycle of 5 ms after the chip select rises, with WIP set.
 *   --chips DIR keeps its memory in DIR/spi<bus>-<pin>.bin.
 *
 * Any other I2C address has no chip: nothing acknowledges it; any other
 * chip select selects nothing: the SPI reads 0xFF.
 */
#ifndef AVR_CHIPS_H
#define AVR_CHIPS_H

#include "sim_avr.h"

#include <stdbool.h>
#include <stdint.h>

/* Attach the chips of sim_chips[] to the MCU's TWI and SPI; load the
 * EEPROMs' memories from `dir` (NULL: erased). False after reporting an
 * error. */
bool sim_chips_init(avr_t *avr, const char *dir);

/* Set the temperature of the sensor at `address` on bus `bus`, in 1/16
 * degC. False (reported, naming `what`) for a temperature the chip cannot
 * measure. */
bool sim_chips_temperature(uint8_t bus, uint8_t address, int32_t sixteenths, const char *what);

/* Write the EEPROMs' memories to the folder given to sim_chips_init (if
 * any). False after reporting an error. */
bool sim_chips_save(void);

#endif /* AVR_CHIPS_H */
