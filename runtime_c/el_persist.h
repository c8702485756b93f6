/* EasyLab runtime: `persist` params in non-volatile storage (docs/service.md,
 * "Persistence").
 *
 * Every persist param has a pair of records, copy A and copy B, at
 * nv_base + EL_PERSIST_SLOT * nv_slot of el_port_nv_read/write (EEPROM on
 * MCUs, the --nvram file on the host). A record is EL_PERSIST_RECORD bytes,
 * little-endian:
 *
 *   0  uint16  sequence number (wraps; the newer of two is the one for which
 *              (int16)(a - b) > 0)
 *   2  uint16  key: CRC-16 of "name:type", so a record never loads into
 *              another param after the model changed
 *   4  uint32  the value (el_service_bits: bool 0/1, integers extended to
 *              32 bits, float32 as IEEE bits)
 *   8  uint16  CRC-16/MODBUS of bytes 0..7
 *
 * A write goes to the copy that is not current, with the next sequence
 * number; the current copy is never touched. A reset or power loss in the
 * middle of a write leaves that copy torn (its CRC fails) or complete, so
 * at boot the newest valid copy holds the old or the new value, never
 * garbage. A value is stored only when it differs from the one stored.
 * Records that are invalid, belong to another key or hold a value outside
 * the param's type or range are ignored: the param keeps its initial
 * value (and its next write gets a sequence number above theirs, so that
 * they never come back).
 */
#ifndef EL_PERSIST_H
#define EL_PERSIST_H

#include "el_types.h"
#include "el_service.h"

#define EL_PERSIST_RECORD 10u
#define EL_PERSIST_SLOT (2u * EL_PERSIST_RECORD)
#define EL_PERSIST_NO_COPY 0xFFu

/* Load every persist param of `map` from storage (at boot). */
void el_persist_load(const el_svc_map_t *map);

/* Store the value `bits` of map id `id` if it differs from the stored one.
 * Returns false when the storage failed. */
bool el_persist_store(const el_svc_map_t *map, uint16_t id, uint32_t bits);

/* Encode a record (for tests and tools): seq, key, value -> 10 bytes. */
void el_persist_encode(uint8_t record[EL_PERSIST_RECORD], uint16_t seq, uint16_t key, uint32_t value);

/* Decode and check a record: true when its CRC holds and its key is `key`. */
bool el_persist_decode(const uint8_t record[EL_PERSIST_RECORD], uint16_t key, uint16_t *seq, uint32_t *value);

#endif /* EL_PERSIST_H */
