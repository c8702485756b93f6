/* EasyLab AVR driver "i2c_eeprom_log" (std's I2cEepromLog): a log of
 * records in a 24LC256-class I2C EEPROM (runtime_c/el_bus.h, avr_twi.c;
 * the layout: docs/stdlib.md).
 *
 * The memory is a ring of slots of `slot` bytes (a power of two that holds
 * a record and divides the page, so a record is one page write). A record
 * is a sequence number (uint16, little-endian; 0xFFFF never: erased
 * memory) and the record's `values` int16, little-endian. open() finds the
 * newest record with a binary search over the slots' sequence numbers (a
 * few reads at boot) and the log goes on after it. write() queues the
 * record as one job and returns: the EEPROM takes it over the bus in the
 * background and is busy for its write cycle (up to 5 ms) afterwards, when
 * the bus tries it again (EL_I2C_RETRY_BUSY) after the other devices' jobs.
 * A record that comes while the previous one is still pending is dropped
 * and counted (`dropped`), never silent. */
#ifndef EL_DRV_I2C_EEPROM_LOG_H
#define EL_DRV_I2C_EEPROM_LOG_H

#include "el_bus.h"

/* The largest record: a sequence number and 31 values (a 64-byte slot). */
#define EL_DRV_I2C_EEPROM_LOG_MAX 64u

typedef struct {
    el_i2c_job_t job;
    uint8_t buf[2u + EL_DRV_I2C_EEPROM_LOG_MAX]; /* the memory address, then the record */
    uint16_t next;    /* the slot the next record goes to */
    uint16_t seq;     /* its sequence number */
    uint16_t dropped; /* records that came while one was pending (saturating) */
} el_drv_i2c_eeprom_log_state_t;

typedef struct {
    uint8_t bus;
    uint8_t address;
    uint8_t values;      /* int16 per record */
    uint8_t slot;        /* bytes per slot */
    uint16_t slots;      /* slots in the memory */
    el_drv_i2c_eeprom_log_state_t *state;
    const int16_t *record; /* `in int16 rate values` */
} el_drv_i2c_eeprom_log_t;

#define EL_DRV_I2C_EEPROM_LOG_EMPTY 0xFFFFu

/* The sequence number in slot k (EMPTY when it cannot be read). */
static inline uint16_t el_drv_i2c_eeprom_log_seq(const el_drv_i2c_eeprom_log_t *d, uint16_t k)
{
    uint32_t at = (uint32_t)k * d->slot;
    uint8_t addr[2];
    uint8_t seq[2];
    addr[0] = (uint8_t)(at >> 8);
    addr[1] = (uint8_t)at;
    if (el_i2c_transfer(d->bus, d->address, addr, 2u, seq, 2u) != EL_BUS_DONE) {
        return EL_DRV_I2C_EEPROM_LOG_EMPTY;
    }
    return (uint16_t)((uint16_t)seq[1] << 8 | seq[0]);
}

static inline uint16_t el_drv_i2c_eeprom_log_after(uint16_t seq)
{
    return seq == 0xFFFEu ? 0u : (uint16_t)(seq + 1u);
}

/* Slots 0..k written in sequence from slot 0's record: the log's newest
 * record is the last slot k for which this holds (the slots after it are
 * erased or older, from the ring's last round). */
static inline void el_drv_i2c_eeprom_log_open(const el_drv_i2c_eeprom_log_t *d)
{
    el_drv_i2c_eeprom_log_state_t *s = d->state;
    uint16_t first = el_drv_i2c_eeprom_log_seq(d, 0u);
    uint16_t lo = 0u, hi = d->slots; /* slots below lo follow slot 0; slots from hi on do not */
    s->dropped = 0u;
    if (first == EL_DRV_I2C_EEPROM_LOG_EMPTY) {
        s->next = 0u;
        s->seq = 0u;
        return;
    }
    lo = 1u;
    while (lo < hi) {
        uint16_t mid = (uint16_t)(lo + (hi - lo) / 2u);
        uint16_t seq = el_drv_i2c_eeprom_log_seq(d, mid);
        uint16_t want = (uint16_t)(first + mid);
        if (first > 0xFFFEu - mid) { /* the numbers skip 0xFFFF */
            want = (uint16_t)(want + 1u);
        }
        if (seq == want) {
            lo = (uint16_t)(mid + 1u);
        } else {
            hi = mid;
        }
    }
    /* lo: the first slot that does not follow; the newest record is before it. */
    s->next = lo == d->slots ? 0u : lo;
    s->seq = el_drv_i2c_eeprom_log_after(el_drv_i2c_eeprom_log_seq(d, (uint16_t)(lo - 1u)));
}

static inline void el_drv_i2c_eeprom_log_start(const el_drv_i2c_eeprom_log_t *d)
{
    (void)d;
}

static inline void el_drv_i2c_eeprom_log_read(const el_drv_i2c_eeprom_log_t *d)
{
    (void)d;
}

static inline void el_drv_i2c_eeprom_log_write(const el_drv_i2c_eeprom_log_t *d)
{
    el_drv_i2c_eeprom_log_state_t *s = d->state;
    uint32_t at = (uint32_t)s->next * d->slot;
    uint8_t i;
    if (s->job.status == EL_BUS_PENDING) {
        if (s->dropped != 0xFFFFu) {
            s->dropped++;
        }
        return;
    }
    s->buf[0] = (uint8_t)(at >> 8);
    s->buf[1] = (uint8_t)at;
    s->buf[2] = (uint8_t)s->seq;
    s->buf[3] = (uint8_t)(s->seq >> 8);
    for (i = 0u; i < d->values; i++) {
        uint16_t v = (uint16_t)d->record[i];
        s->buf[4u + 2u * i] = (uint8_t)v;
        s->buf[5u + 2u * i] = (uint8_t)(v >> 8);
    }
    s->job.bus = d->bus;
    s->job.address = d->address;
    s->job.flags = EL_I2C_RETRY_BUSY;
    s->job.tx = s->buf;
    s->job.tx_len = (uint8_t)(4u + 2u * d->values);
    s->job.rx = 0;
    s->job.rx_len = 0u;
    if (el_i2c_submit(&s->job)) {
        s->seq = el_drv_i2c_eeprom_log_after(s->seq);
        s->next = (uint16_t)(s->next + 1u) == d->slots ? 0u : (uint16_t)(s->next + 1u);
    }
}

static inline void el_drv_i2c_eeprom_log_stop(const el_drv_i2c_eeprom_log_t *d)
{
    (void)el_i2c_wait(&d->state->job); /* the last record reaches the memory */
}

static inline void el_drv_i2c_eeprom_log_close(const el_drv_i2c_eeprom_log_t *d)
{
    (void)d;
}

#endif /* EL_DRV_I2C_EEPROM_LOG_H */
