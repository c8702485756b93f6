/* EasyLab AVR drivers: the log of std's EEPROM log devices (I2cEepromLog,
 * SpiEepromLog: el_drv_i2c_eeprom_log.h, el_drv_spi_eeprom_log.h), whatever
 * the bus. The layout (docs/stdlib.md, "EEPROM logs"):
 *
 * The memory is a ring of slots of `slot` bytes (a power of two that holds
 * a record and divides the page, so a record is one page write). A record
 * is a sequence number (uint16, little-endian; never 0xFFFF, the value of
 * erased memory) and the record's `values` int16, little-endian. After a
 * reset the log goes on after its newest record, found by a binary search
 * over the slots' sequence numbers: slots 0..k hold numbers that follow
 * slot 0's one by one, the slots after the newest are erased or older.
 */
#ifndef EL_DRV_EEPROM_LOG_H
#define EL_DRV_EEPROM_LOG_H

#include "el_types.h"

#define EL_EEPROM_LOG_EMPTY 0xFFFFu
/* The largest record: a sequence number and 31 values (a 64-byte slot). */
#define EL_EEPROM_LOG_MAX 64u

typedef struct {
    uint16_t next;    /* the slot the next record goes to */
    uint16_t seq;     /* its sequence number */
    uint16_t dropped; /* records that could not be written (saturating) */
} el_eeprom_log_t;

/* A log's layout in its memory, and its device's record. */
typedef struct {
    uint8_t values;        /* int16 per record */
    uint8_t slot;          /* bytes per slot */
    uint16_t slots;        /* slots in the memory */
    const int16_t *record; /* the device's `in int16 rate values` */
} el_eeprom_log_layout_t;

/* The sequence number in slot k of a device's memory (EMPTY when it cannot
 * be read). */
typedef uint16_t (*el_eeprom_log_seq_t)(const void *device, uint16_t k);

static inline uint16_t el_eeprom_log_after(uint16_t seq)
{
    return seq == 0xFFFEu ? 0u : (uint16_t)(seq + 1u);
}

/* Where the log goes on: after its newest record, or at slot 0. */
static inline void el_eeprom_log_find(el_eeprom_log_t *log, uint16_t slots, el_eeprom_log_seq_t seq_at,
                                      const void *device)
{
    uint16_t first = seq_at(device, 0u);
    uint16_t lo = 1u, hi = slots; /* slots below lo follow slot 0; slots from hi on do not */
    log->dropped = 0u;
    if (first == EL_EEPROM_LOG_EMPTY) {
        log->next = 0u;
        log->seq = 0u;
        return;
    }
    while (lo < hi) {
        uint16_t mid = (uint16_t)(lo + (hi - lo) / 2u);
        uint16_t want = (uint16_t)(first + mid);
        if (first > 0xFFFEu - mid) { /* the numbers skip 0xFFFF */
            want = (uint16_t)(want + 1u);
        }
        if (seq_at(device, mid) == want) {
            lo = (uint16_t)(mid + 1u);
        } else {
            hi = mid;
        }
    }
    /* lo: the first slot that does not follow; the newest record is before it. */
    log->next = lo == slots ? 0u : lo;
    log->seq = el_eeprom_log_after(seq_at(device, (uint16_t)(lo - 1u)));
}

/* The memory address of the next record's slot. */
static inline uint32_t el_eeprom_log_address(const el_eeprom_log_t *log, const el_eeprom_log_layout_t *layout)
{
    return (uint32_t)log->next * layout->slot;
}

/* The next record into `buf` (sequence number, then the device's values);
 * returns its bytes. */
static inline uint8_t el_eeprom_log_record(const el_eeprom_log_t *log, const el_eeprom_log_layout_t *layout,
                                           uint8_t *buf)
{
    uint8_t i;
    buf[0] = (uint8_t)log->seq;
    buf[1] = (uint8_t)(log->seq >> 8);
    for (i = 0u; i < layout->values; i++) {
        uint16_t v = (uint16_t)layout->record[i];
        buf[2u + 2u * i] = (uint8_t)v;
        buf[3u + 2u * i] = (uint8_t)(v >> 8);
    }
    return (uint8_t)(2u + 2u * layout->values);
}

/* The record went to the memory: the next slot, the next number. */
static inline void el_eeprom_log_advance(el_eeprom_log_t *log, uint16_t slots)
{
    log->seq = el_eeprom_log_after(log->seq);
    log->next = (uint16_t)(log->next + 1u) == slots ? 0u : (uint16_t)(log->next + 1u);
}

static inline void el_eeprom_log_drop(el_eeprom_log_t *log)
{
    if (log->dropped != 0xFFFFu) {
        log->dropped++;
    }
}

#endif /* EL_DRV_EEPROM_LOG_H */
