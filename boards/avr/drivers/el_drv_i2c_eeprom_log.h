/* EasyLab AVR driver "i2c_eeprom_log" (std's I2cEepromLog): a log of
 * records (el_drv_eeprom_log.h) in a 24LC256-class I2C EEPROM
 * (runtime_c/el_bus.h, avr_twi.c).
 *
 * open() finds where the log goes on (a few reads at boot). write() queues
 * the record as one page write and returns: the EEPROM takes it over the
 * bus in the background and is busy for its write cycle (up to 5 ms)
 * afterwards, when the bus tries it again (EL_I2C_RETRY_BUSY) after the
 * other devices' jobs. A record that comes while the previous one is still
 * pending is dropped and counted, never silent; stop() waits for the last. */
#ifndef EL_DRV_I2C_EEPROM_LOG_H
#define EL_DRV_I2C_EEPROM_LOG_H

#include "el_bus.h"
#include "el_driver.h"
#include "el_drv_eeprom_log.h"

typedef struct {
    el_eeprom_log_t log;
    el_i2c_job_t job;
    uint8_t buf[2u + EL_EEPROM_LOG_MAX]; /* the memory address, then the record */
} el_drv_i2c_eeprom_log_state_t;

typedef struct {
    uint8_t bus;
    uint8_t address;
    el_eeprom_log_layout_t layout;
    el_drv_i2c_eeprom_log_state_t *state;
} el_drv_i2c_eeprom_log_t;

static inline uint16_t el_drv_i2c_eeprom_log_seq(const void *device, uint16_t k)
{
    const el_drv_i2c_eeprom_log_t *d = (const el_drv_i2c_eeprom_log_t *)device;
    uint32_t at = (uint32_t)k * d->layout.slot;
    uint8_t addr[2];
    uint8_t seq[2];
    addr[0] = (uint8_t)(at >> 8);
    addr[1] = (uint8_t)at;
    if (el_i2c_transfer(d->bus, d->address, addr, 2u, seq, 2u) != EL_BUS_DONE) {
        return EL_EEPROM_LOG_EMPTY;
    }
    return (uint16_t)((uint16_t)seq[1] << 8 | seq[0]);
}

static inline void el_drv_i2c_eeprom_log_open(const el_drv_i2c_eeprom_log_t *d)
{
    el_eeprom_log_find(&d->state->log, d->layout.slots, el_drv_i2c_eeprom_log_seq, d);
}

EL_DRV_NOTHING(el_drv_i2c_eeprom_log_start, el_drv_i2c_eeprom_log_t)
EL_DRV_NOTHING(el_drv_i2c_eeprom_log_read, el_drv_i2c_eeprom_log_t)

static inline void el_drv_i2c_eeprom_log_write(const el_drv_i2c_eeprom_log_t *d)
{
    el_drv_i2c_eeprom_log_state_t *s = d->state;
    uint32_t at = el_eeprom_log_address(&s->log, &d->layout);
    if (s->job.status == EL_BUS_PENDING) {
        el_eeprom_log_drop(&s->log);
        return;
    }
    s->buf[0] = (uint8_t)(at >> 8);
    s->buf[1] = (uint8_t)at;
    s->job.bus = d->bus;
    s->job.address = d->address;
    s->job.flags = EL_I2C_RETRY_BUSY;
    s->job.tx = s->buf;
    s->job.tx_len = (uint8_t)(2u + el_eeprom_log_record(&s->log, &d->layout, s->buf + 2));
    s->job.rx = 0;
    s->job.rx_len = 0u;
    if (el_i2c_submit(&s->job)) {
        el_eeprom_log_advance(&s->log, d->layout.slots);
    } else {
        el_eeprom_log_drop(&s->log);
    }
}

static inline void el_drv_i2c_eeprom_log_stop(const el_drv_i2c_eeprom_log_t *d)
{
    (void)el_i2c_wait(&d->state->job); /* the last record reaches the memory */
}

EL_DRV_NOTHING(el_drv_i2c_eeprom_log_close, el_drv_i2c_eeprom_log_t)

#endif /* EL_DRV_I2C_EEPROM_LOG_H */
