/* EasyLab AVR driver "spi_eeprom_log" (std's SpiEepromLog): a log of
 * records (el_drv_eeprom_log.h) in a 25LC256-class SPI EEPROM
 * (runtime_c/el_bus.h, avr_spi.c; SPI mode 0).
 *
 * open() configures the chip select and finds where the log goes on.
 * write() reads the chip's status: while its write cycle (up to 5 ms) is
 * still under way the record is dropped and counted, never silent;
 * otherwise it enables writing (WREN) and sends the record as one page
 * write (WRITE), about 2 us a byte: the chip writes it on its own. */
#ifndef EL_DRV_SPI_EEPROM_LOG_H
#define EL_DRV_SPI_EEPROM_LOG_H

#include "el_bus.h"
#include "el_driver.h"
#include "el_drv_eeprom_log.h"

#define EL_DRV_SPI_EEPROM_READ 0x03u
#define EL_DRV_SPI_EEPROM_WRITE 0x02u
#define EL_DRV_SPI_EEPROM_WREN 0x06u
#define EL_DRV_SPI_EEPROM_RDSR 0x05u
#define EL_DRV_SPI_EEPROM_WIP 0x01u /* the status: a write cycle under way */

typedef struct {
    el_eeprom_log_t log;
} el_drv_spi_eeprom_log_state_t;

typedef struct {
    uint8_t bus;
    el_pin_t cs;
    el_eeprom_log_layout_t layout;
    el_drv_spi_eeprom_log_state_t *state;
} el_drv_spi_eeprom_log_t;

static inline uint16_t el_drv_spi_eeprom_log_seq(const void *device, uint16_t k)
{
    const el_drv_spi_eeprom_log_t *d = (const el_drv_spi_eeprom_log_t *)device;
    uint32_t at = (uint32_t)k * d->layout.slot;
    uint8_t io[5];
    io[0] = EL_DRV_SPI_EEPROM_READ;
    io[1] = (uint8_t)(at >> 8);
    io[2] = (uint8_t)at;
    io[3] = 0xFFu;
    io[4] = 0xFFu;
    if (el_spi_transfer(d->bus, &d->cs, EL_SPI_MODE0, io, io, 5u) != EL_BUS_DONE) {
        return EL_EEPROM_LOG_EMPTY;
    }
    return (uint16_t)((uint16_t)io[4] << 8 | io[3]);
}

static inline void el_drv_spi_eeprom_log_open(const el_drv_spi_eeprom_log_t *d)
{
    (void)el_spi_open(d->bus, &d->cs);
    el_eeprom_log_find(&d->state->log, d->layout.slots, el_drv_spi_eeprom_log_seq, d);
}

EL_DRV_NOTHING(el_drv_spi_eeprom_log_start, el_drv_spi_eeprom_log_t)
EL_DRV_NOTHING(el_drv_spi_eeprom_log_read, el_drv_spi_eeprom_log_t)

static inline void el_drv_spi_eeprom_log_write(const el_drv_spi_eeprom_log_t *d)
{
    el_drv_spi_eeprom_log_state_t *s = d->state;
    uint32_t at = el_eeprom_log_address(&s->log, &d->layout);
    uint8_t buf[3u + EL_EEPROM_LOG_MAX];
    uint8_t status[2] = {EL_DRV_SPI_EEPROM_RDSR, 0xFFu};
    static const uint8_t wren = EL_DRV_SPI_EEPROM_WREN;
    if (el_spi_transfer(d->bus, &d->cs, EL_SPI_MODE0, status, status, 2u) != EL_BUS_DONE ||
        (status[1] & EL_DRV_SPI_EEPROM_WIP) != 0u) {
        el_eeprom_log_drop(&s->log);
        return;
    }
    buf[0] = EL_DRV_SPI_EEPROM_WRITE;
    buf[1] = (uint8_t)(at >> 8);
    buf[2] = (uint8_t)at;
    (void)el_spi_transfer(d->bus, &d->cs, EL_SPI_MODE0, &wren, (uint8_t *)0, 1u);
    (void)el_spi_transfer(d->bus, &d->cs, EL_SPI_MODE0, buf, (uint8_t *)0,
                          (uint16_t)(3u + el_eeprom_log_record(&s->log, &d->layout, buf + 3)));
    el_eeprom_log_advance(&s->log, d->layout.slots);
}

EL_DRV_NOTHING(el_drv_spi_eeprom_log_stop, el_drv_spi_eeprom_log_t)
EL_DRV_NOTHING(el_drv_spi_eeprom_log_close, el_drv_spi_eeprom_log_t)

#endif /* EL_DRV_SPI_EEPROM_LOG_H */
