/* EasyLab runtime: persist params, two checksummed copies with a sequence
 * number (see el_persist.h). */
#include "el_persist.h"
#include "el_crc16.h"
#include "el_port.h"

void el_persist_encode(uint8_t record[EL_PERSIST_RECORD], uint16_t seq, uint16_t key, uint32_t value)
{
    uint16_t crc;
    record[0] = (uint8_t)(seq & 0xFFu);
    record[1] = (uint8_t)(seq >> 8);
    record[2] = (uint8_t)(key & 0xFFu);
    record[3] = (uint8_t)(key >> 8);
    record[4] = (uint8_t)(value & 0xFFu);
    record[5] = (uint8_t)((value >> 8) & 0xFFu);
    record[6] = (uint8_t)((value >> 16) & 0xFFu);
    record[7] = (uint8_t)((value >> 24) & 0xFFu);
    crc = el_crc16(record, 8u);
    record[8] = (uint8_t)(crc & 0xFFu);
    record[9] = (uint8_t)(crc >> 8);
}

bool el_persist_decode(const uint8_t record[EL_PERSIST_RECORD], uint16_t key, uint16_t *seq, uint32_t *value)
{
    uint16_t crc = (uint16_t)(record[8] | ((uint16_t)record[9] << 8));
    if (el_crc16(record, 8u) != crc)
        return false;
    if ((uint16_t)(record[2] | ((uint16_t)record[3] << 8)) != key)
        return false;
    *seq = (uint16_t)(record[0] | ((uint16_t)record[1] << 8));
    *value = (uint32_t)record[4] | ((uint32_t)record[5] << 8) | ((uint32_t)record[6] << 16) |
             ((uint32_t)record[7] << 24);
    return true;
}

static uint16_t record_offset(const el_svc_map_t *map, const el_svc_entry_t *e, uint8_t copy)
{
    return (uint16_t)(map->nv_base + e->nv_slot * EL_PERSIST_SLOT + copy * EL_PERSIST_RECORD);
}

/* What read_copy found. */
#define COPY_BAD 0u      /* unreadable, CRC or key wrong */
#define COPY_REJECTED 1u /* a record of this param, but a value it does not accept (now) */
#define COPY_GOOD 2u

/* Read copy `copy` of an entry. */
static uint8_t read_copy(const el_svc_map_t *map, uint16_t id, uint8_t copy, uint16_t *seq, uint32_t *value)
{
    const el_svc_entry_t *e = &map->entries[id];
    uint8_t record[EL_PERSIST_RECORD];
    el_svc_value_t v;
    if (!el_port_nv_read(record_offset(map, e, copy), record, EL_PERSIST_RECORD))
        return COPY_BAD;
    if (!el_persist_decode(record, e->nv_key, seq, value))
        return COPY_BAD;
    el_service_from_bits(e->type, *value, &v);
    return el_service_check(id, &v) == EL_SVC_OK ? COPY_GOOD : COPY_REJECTED;
}

/* seq b is newer than seq a (wrap-safe). */
static bool newer(uint16_t b, uint16_t a)
{
    return (uint16_t)(b - a) != 0u && (uint16_t)(b - a) < 0x8000u;
}

void el_persist_load(const el_svc_map_t *map)
{
    uint16_t id;
    if (map == (const el_svc_map_t *)0)
        return;
    for (id = 0u; id < map->count; id++) {
        const el_svc_entry_t *e = &map->entries[id];
        el_svc_nv_t *nv;
        uint16_t seq[2] = {0u, 0u};
        uint32_t val[2] = {0u, 0u};
        uint8_t got[2], c;
        if ((e->flags & EL_SVC_F_PERSIST) == 0u || e->nv_slot >= map->nv_count)
            continue;
        nv = &map->nv[e->nv_slot];
        nv->current = EL_PERSIST_NO_COPY;
        nv->seq = 0u;
        nv->value = 0u;
        got[0] = read_copy(map, id, 0u, &seq[0], &val[0]);
        got[1] = read_copy(map, id, 1u, &seq[1], &val[1]);
        /* The newest good copy holds the value. */
        for (c = 0u; c < 2u; c++) {
            if (got[c] == COPY_GOOD && (nv->current == EL_PERSIST_NO_COPY || newer(seq[c], nv->seq))) {
                nv->current = c;
                nv->seq = seq[c];
                nv->value = val[c];
            }
        }
        if (nv->current == EL_PERSIST_NO_COPY) {
            /* Records this param's values no longer fit: the next write must
             * still be newer than them, or they would come back one day. */
            for (c = 0u; c < 2u; c++)
                if (got[c] == COPY_REJECTED && newer(seq[c], nv->seq))
                    nv->seq = seq[c];
            continue;
        }
        {
            el_svc_value_t v;
            el_service_from_bits(e->type, nv->value, &v);
            (void)el_service_write(id, &v);
        }
    }
}

bool el_persist_store(const el_svc_map_t *map, uint16_t id, uint32_t bits)
{
    const el_svc_entry_t *e;
    el_svc_nv_t *nv;
    uint8_t record[EL_PERSIST_RECORD];
    uint8_t copy;
    uint16_t seq;
    if (map == (const el_svc_map_t *)0 || id >= map->count)
        return false;
    e = &map->entries[id];
    if ((e->flags & EL_SVC_F_PERSIST) == 0u || e->nv_slot >= map->nv_count)
        return true;
    nv = &map->nv[e->nv_slot];
    if (nv->current != EL_PERSIST_NO_COPY && nv->value == bits)
        return true; /* unchanged: storage is written only on change */
    /* Never overwrite the current copy: write the other one, newer. */
    copy = nv->current == 0u ? 1u : 0u;
    seq = (uint16_t)(nv->seq + 1u);
    el_persist_encode(record, seq, e->nv_key, bits);
    if (!el_port_nv_write(record_offset(map, e, copy), record, EL_PERSIST_RECORD))
        return false;
    nv->current = copy;
    nv->seq = seq;
    nv->value = bits;
    return true;
}
