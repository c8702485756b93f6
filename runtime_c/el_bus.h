/* EasyLab runtime: the buses of a board (optional part of the port
 * interface; docs/boards.md, "Buses").
 *
 * Devices on a shared bus (`claims i2c[0] addr 0x48`) talk to their chips
 * through these functions: the board's drivers, and the handler files a
 * model brings (docs/language.md, "Device handlers"). A board with I2C
 * implements them in its folder (the AVR board on its TWI, avr_twi.c);
 * nothing else in the runtime calls them, so boards without buses need
 * nothing.
 *
 * I2C transfers never block the CPU: the board runs a bus's jobs one after the
 * other from its interrupts, in the order they were submitted. A job is
 * the caller's (static, in a driver's state, or on the stack while its
 * caller waits): no heap. Whoever waits for a job waits at most the bus's
 * bound, EL_I2C_WAIT_US microseconds (the board's, at least the time of a
 * read of a few bytes plus the longest transfer that may be under way);
 * after it the job is abandoned (EL_BUS_TIMEOUT) and the bus is free for
 * the next. The logical-time rule that follows (docs/ir.md, "Devices on a
 * bus"): a device's read() finishes its transfer within the instant, so
 * its data are sampled at the instant, as any device's.
 */
#ifndef EL_BUS_H
#define EL_BUS_H

#include "el_types.h"

/* A job's status. */
typedef uint8_t el_bus_status_t;
#define EL_BUS_DONE 0u    /* every byte went (and came) */
#define EL_BUS_PENDING 1u /* queued, or on the bus now */
#define EL_BUS_NACK 2u    /* the chip did not acknowledge its address or a byte */
#define EL_BUS_TIMEOUT 3u /* not done within the bound: abandoned, the bus reset */
#define EL_BUS_ERROR 4u   /* a bus error, lost arbitration, or a job the bus cannot run */

/* Job flags. */
#define EL_I2C_RETRY_BUSY 0x01u /* a chip that does not acknowledge its address is busy (an
                                 * EEPROM's write cycle): try again after the jobs queued
                                 * meanwhile, for at most EL_I2C_BUSY_US */

/* One I2C transaction: START, the address with W and `tx_len` bytes from
 * `tx` (if any), then (a repeated START if it wrote) the address with R and
 * `rx_len` bytes into `rx` (if any), STOP. 7-bit addresses. */
typedef struct el_i2c_job {
    uint8_t bus;        /* i2c[bus] */
    uint8_t address;    /* 0x08..0x77 */
    uint8_t flags;      /* EL_I2C_... */
    const uint8_t *tx;
    uint8_t tx_len;
    uint8_t *rx;
    uint8_t rx_len;
    volatile el_bus_status_t status;
    /* The bus's own from here on. */
    uint32_t since;     /* when it was submitted (the board's fine clock) */
    struct el_i2c_job *volatile next;
} el_i2c_job_t;

/* Queue a job (status EL_BUS_PENDING) and return at once. False for a job
 * still pending (queued already: left as it is) and, with status
 * EL_BUS_ERROR, for a job the bus cannot run (no such bus, an address
 * above 0x7F, a buffer missing). A new job starts with any status but
 * EL_BUS_PENDING (zeroed: EL_BUS_DONE). */
bool el_i2c_submit(el_i2c_job_t *job);

/* Wait until the job is no longer pending, at most EL_I2C_WAIT_US from
 * now; a job still pending then is abandoned (EL_BUS_TIMEOUT). Returns its
 * status. */
el_bus_status_t el_i2c_wait(el_i2c_job_t *job);

/* Submit and wait: a write of `tx_len` bytes then a read of `rx_len`
 * bytes (either may be 0), with a job of its own. */
el_bus_status_t el_i2c_transfer(uint8_t bus, uint8_t address, const uint8_t *tx, uint8_t tx_len, uint8_t *rx,
                                uint8_t rx_len);

/* Jobs that failed on a bus (NACK, timeout, bus error), saturating. */
uint16_t el_i2c_errors(uint8_t bus);

/* ---- SPI (master) ----
 *
 * A device on an SPI bus (`claims spi[0] cs "PB2"`) is selected by its own
 * pin: the board describes it (struct el_pin, in the board's el_board.h),
 * and a device's handlers get theirs as EL_CS. SPI clocks bytes in
 * microseconds (2 us at 4 MHz), so a transfer is done in place, its
 * duration bounded by its length: len * 8 / EL_SPI_HZ seconds (plus a few
 * cycles a byte). */

typedef struct el_pin el_pin_t;

/* SPI modes: clock polarity and phase. */
#define EL_SPI_MODE0 0u /* clock idle low, sample on the rising edge */
#define EL_SPI_MODE1 1u /* clock idle low, sample on the falling edge */
#define EL_SPI_MODE2 2u /* clock idle high, sample on the falling edge */
#define EL_SPI_MODE3 3u /* clock idle high, sample on the rising edge */

/* Make the bus ready and the chip select an output, high (not selected):
 * a device's open() calls it before the device's first transfer. */
el_bus_status_t el_spi_open(uint8_t bus, const el_pin_t *cs);

/* One transfer, most significant bit first: the chip select low, `len`
 * bytes out from `tx` (0xFF each when tx is NULL) while as many come in
 * to `rx` (dropped when NULL), the chip select high. EL_BUS_ERROR for a bus
 * the board lacks or no chip select. */
el_bus_status_t el_spi_transfer(uint8_t bus, const el_pin_t *cs, uint8_t mode, const uint8_t *tx, uint8_t *rx,
                                uint16_t len);

#endif /* EL_BUS_H */
