/* EasyLab runtime: the Modbus slave (see el_modbus.h). Everything that
 * comes from outside is bounds-checked here: request lengths, quantities,
 * byte counts and address ranges, before anything is written (a read
 * checks each address as it fills the response: it changes nothing). */
#include "el_modbus.h"
#include "el_crc16.h"
#include "el_service.h"
#include "el_model.h" /* EL_T_... */

#define NOT_FOUND 0xFFFFu
#define ID_STRING_MAX 244u /* one object always fits in a response */

static uint16_t get16(const uint8_t *p)
{
    return (uint16_t)(((uint16_t)p[0] << 8) | p[1]);
}

static void put16(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)(v >> 8);
    p[1] = (uint8_t)(v & 0xFFu);
}

static uint16_t exception(uint8_t fc, uint8_t code, uint8_t *resp)
{
    resp[0] = (uint8_t)(fc | 0x80u);
    resp[1] = code;
    return 2u;
}

/* Addresses an entry takes in its table: 1 bit, or 1 or 2 registers. */
static uint8_t span(const el_svc_entry_t *e)
{
    uint8_t r = el_service_regs(e->type);
    return r == 0u ? 1u : r;
}

static const el_svc_entry_t *at(const el_svc_map_t *m, uint16_t k)
{
    return &m->entries[m->order[k]];
}

/* The position in m->order of the entry of table t that covers `address`,
 * or NOT_FOUND. Entries of a table are sorted and never overlap. */
static uint16_t locate(const el_svc_map_t *m, uint8_t t, uint16_t address)
{
    const el_svc_entry_t *entries = m->entries;
    const uint16_t *order = m->order + m->first[t];
    uint16_t lo = 0u, hi = m->size[t];
    const el_svc_entry_t *e;
    while (lo < hi) { /* the first entry starting above `address` */
        uint16_t mid = (uint16_t)(lo + (hi - lo) / 2u);
        if (entries[order[mid]].address <= address)
            lo = (uint16_t)(mid + 1u);
        else
            hi = mid;
    }
    if (lo == 0u)
        return NOT_FOUND;
    e = &entries[order[lo - 1u]];
    return (uint32_t)address < (uint32_t)e->address + span(e) ? (uint16_t)(m->first[t] + lo - 1u) : NOT_FOUND;
}

/* The entry covering `address`, the one after `k` (which covers
 * address - 1): k itself, the next entry when it starts right there, or
 * NOT_FOUND at a hole or the table's end. */
static uint16_t next_cover(const el_svc_map_t *m, uint8_t t, uint16_t k, uint16_t address)
{
    const el_svc_entry_t *e = at(m, k);
    if ((uint32_t)address < (uint32_t)e->address + span(e))
        return k;
    if ((uint16_t)(k + 1u) >= (uint16_t)(m->first[t] + m->size[t]))
        return NOT_FOUND;
    return at(m, (uint16_t)(k + 1u))->address == address ? (uint16_t)(k + 1u) : NOT_FOUND;
}

/* Every address of [start, start + qty) is in table t. */
static bool covered(const el_svc_map_t *m, uint8_t t, uint16_t start, uint16_t qty)
{
    uint16_t i, k = locate(m, t, start);
    for (i = 1u; i < qty && k != NOT_FOUND; i++)
        k = next_cover(m, t, k, (uint16_t)(start + i));
    return k != NOT_FOUND;
}

/* The checks every read request (01 to 04) passes first, in the
 * specification's order: length and quantity (03), then the end of the
 * address range (02). Returns 0 with *start and *qty set, or the length of
 * the exception response. That every address is served (02 too) is checked
 * while the response is filled: a read changes nothing, so a hole found
 * half-way still answers with nothing but the exception. */
static uint16_t check_read(uint8_t fc, const uint8_t *req, uint16_t len, uint16_t max_qty, uint8_t *resp,
                           uint16_t *start, uint16_t *qty)
{
    if (len != 5u)
        return exception(fc, EL_MB_EX_ILLEGAL_VALUE, resp);
    *start = get16(req + 1);
    *qty = get16(req + 3);
    if (*qty < 1u || *qty > max_qty)
        return exception(fc, EL_MB_EX_ILLEGAL_VALUE, resp);
    if ((uint32_t)*start + *qty > 0x10000UL)
        return exception(fc, EL_MB_EX_ILLEGAL_ADDRESS, resp);
    return 0u;
}

/* The entry of table t covering address start + i, from the one covering
 * the address before (k, for i > 0); NOT_FOUND at a hole. */
static uint16_t cover(const el_svc_map_t *m, uint8_t t, uint16_t k, uint16_t start, uint16_t i)
{
    if (i == 0u)
        return locate(m, t, start);
    return next_cover(m, t, k, (uint16_t)(start + i));
}

/* The register at `address` of the entry at position k of m->order. A
 * 16-bit value is its own register (most registers are: read directly);
 * the others go through the service's value conversion. */
static uint16_t register_at(const el_svc_map_t *m, uint16_t k, uint16_t address)
{
    const el_svc_entry_t *e = at(m, k);
    el_svc_value_t v;
    uint16_t regs[2];
    if (e->type == EL_T_I16 || e->type == EL_T_U16)
        return *(const uint16_t *)e->addr; /* int16_t read as uint16_t: the register's bits */
    v.u = 0u;
    (void)el_service_get(m->order[k], &v);
    el_service_to_regs(e->type, &v, regs);
    return regs[(uint16_t)(address - e->address) & 1u];
}

/* ---- 01 / 02: read coils / discrete inputs ---- */
static uint16_t read_bits(const el_svc_map_t *m, uint8_t fc, const uint8_t *req, uint16_t len, uint8_t *resp)
{
    uint8_t t = (uint8_t)(fc == 0x01u ? EL_SVC_COIL : EL_SVC_DISCRETE);
    uint16_t start, qty, i, k = NOT_FOUND, bytes;
    uint16_t refused = check_read(fc, req, len, EL_MB_MAX_READ_BITS, resp, &start, &qty);
    if (refused != 0u)
        return refused;
    bytes = (uint16_t)((qty + 7u) / 8u);
    resp[0] = fc;
    resp[1] = (uint8_t)bytes;
    for (i = 0u; i < bytes; i++)
        resp[2u + i] = 0u;
    for (i = 0u; i < qty; i++) {
        el_svc_value_t v;
        k = cover(m, t, k, start, i);
        if (k == NOT_FOUND)
            return exception(fc, EL_MB_EX_ILLEGAL_ADDRESS, resp);
        if (el_service_get(m->order[k], &v) == EL_SVC_OK && v.u != 0u)
            resp[2u + i / 8u] = (uint8_t)(resp[2u + i / 8u] | (1u << (i % 8u)));
    }
    return (uint16_t)(2u + bytes);
}

/* ---- 03 / 04: read holding / input registers ---- */

/* The fast path of most maps: from position `k` of m->order on (k < end),
 * entries that start at consecutive addresses from `address` and hold a
 * 16-bit item each (its own register), read straight into `out`. Returns
 * how many registers it read, at most n. */
EL_NOINLINE static uint16_t read_run(const el_svc_map_t *m, uint16_t k, uint16_t end, uint16_t address, uint16_t n,
                         uint8_t *out)
{
    const el_svc_entry_t *entries = m->entries;
    const uint16_t *from = m->order + k, *order = from;
    const uint16_t *stop = m->order + ((uint16_t)(end - k) < n ? end : (uint16_t)(k + n));
    for (; order < stop; order++, address++, out += 2) {
        const el_svc_entry_t *e = &entries[*order];
        uint16_t v;
        if (e->address != address || (e->type != EL_T_I16 && e->type != EL_T_U16))
            break;
        v = *(const uint16_t *)e->addr; /* int16_t read as uint16_t: the register's bits */
        out[0] = (uint8_t)(v >> 8);
        out[1] = (uint8_t)(v & 0xFFu);
    }
    return (uint16_t)(order - from);
}

static uint16_t read_regs(const el_svc_map_t *m, uint8_t fc, const uint8_t *req, uint16_t len, uint8_t *resp)
{
    uint8_t t = (uint8_t)(fc == 0x03u ? EL_SVC_HOLDING : EL_SVC_INPUT);
    uint16_t start, qty, i = 0u, k, end;
    uint16_t refused = check_read(fc, req, len, EL_MB_MAX_READ_REGS, resp, &start, &qty);
    if (refused != 0u)
        return refused;
    end = (uint16_t)(m->first[t] + m->size[t]);
    k = locate(m, t, start);
    while (k != NOT_FOUND) {
        /* Entries never overlap: the one at k starts at start + i unless
         * start + i is the second register of a 32-bit item. */
        uint16_t run = read_run(m, k, end, (uint16_t)(start + i), (uint16_t)(qty - i), resp + 2u + 2u * i);
        if (run > 0u) {
            i = (uint16_t)(i + run);
            k = (uint16_t)(k + run - 1u);
        } else {
            put16(resp + 2u + 2u * i, register_at(m, k, (uint16_t)(start + i)));
            i++;
        }
        if (i == qty)
            break;
        k = next_cover(m, t, k, (uint16_t)(start + i));
    }
    if (k == NOT_FOUND)
        return exception(fc, EL_MB_EX_ILLEGAL_ADDRESS, resp);
    resp[0] = fc;
    resp[1] = (uint8_t)(2u * qty);
    return (uint16_t)(2u + 2u * qty);
}

/* Map a service status to a response (0: fine). */
static uint8_t status_exception(el_svc_status_t st)
{
    switch (st) {
    case EL_SVC_OK: return 0u;
    case EL_SVC_STORAGE: return EL_MB_EX_DEVICE_FAILURE;
    case EL_SVC_BAD_VALUE: return EL_MB_EX_ILLEGAL_VALUE;
    default: return EL_MB_EX_ILLEGAL_ADDRESS;
    }
}

static uint16_t echo(const uint8_t *req, uint8_t *resp)
{
    uint8_t i;
    for (i = 0u; i < 5u; i++)
        resp[i] = req[i];
    return 5u;
}

/* ---- 05: write single coil ---- */
static uint16_t write_coil(const el_svc_map_t *m, const uint8_t *req, uint16_t len, uint8_t *resp)
{
    uint16_t address, value, k;
    el_svc_value_t v;
    uint8_t ex;
    if (len != 5u)
        return exception(0x05u, EL_MB_EX_ILLEGAL_VALUE, resp);
    address = get16(req + 1);
    value = get16(req + 3);
    if (value != 0x0000u && value != 0xFF00u)
        return exception(0x05u, EL_MB_EX_ILLEGAL_VALUE, resp);
    k = locate(m, EL_SVC_COIL, address);
    if (k == NOT_FOUND)
        return exception(0x05u, EL_MB_EX_ILLEGAL_ADDRESS, resp);
    v.u = value == 0xFF00u ? 1u : 0u;
    ex = status_exception(el_service_write(m->order[k], &v));
    return ex != 0u ? exception(0x05u, ex, resp) : echo(req, resp);
}

/* ---- 06: write single register ---- */
static uint16_t write_reg(const el_svc_map_t *m, const uint8_t *req, uint16_t len, uint8_t *resp)
{
    uint16_t address, k, regs[2];
    const el_svc_entry_t *e;
    el_svc_value_t v;
    uint8_t ex;
    if (len != 5u)
        return exception(0x06u, EL_MB_EX_ILLEGAL_VALUE, resp);
    address = get16(req + 1);
    k = locate(m, EL_SVC_HOLDING, address);
    e = k != NOT_FOUND ? at(m, k) : (const el_svc_entry_t *)0;
    if (e == (const el_svc_entry_t *)0 || e->address != address || span(e) != 1u)
        return exception(0x06u, EL_MB_EX_ILLEGAL_ADDRESS, resp); /* also half of a 32-bit item */
    regs[0] = get16(req + 3);
    regs[1] = 0u;
    ex = status_exception(el_service_from_regs(e->type, regs, &v));
    if (ex == 0u)
        ex = status_exception(el_service_write(m->order[k], &v));
    return ex != 0u ? exception(0x06u, ex, resp) : echo(req, resp);
}

/* ---- 15: write multiple coils ---- */
static uint16_t write_coils(const el_svc_map_t *m, const uint8_t *req, uint16_t len, uint8_t *resp)
{
    uint16_t start, qty, i, k;
    uint8_t ex = 0u;
    if (len < 6u)
        return exception(0x0Fu, EL_MB_EX_ILLEGAL_VALUE, resp);
    start = get16(req + 1);
    qty = get16(req + 3);
    if (qty < 1u || qty > EL_MB_MAX_WRITE_BITS || req[5] != (qty + 7u) / 8u || len != 6u + req[5])
        return exception(0x0Fu, EL_MB_EX_ILLEGAL_VALUE, resp);
    if ((uint32_t)start + qty > 0x10000UL || !covered(m, EL_SVC_COIL, start, qty))
        return exception(0x0Fu, EL_MB_EX_ILLEGAL_ADDRESS, resp);
    k = locate(m, EL_SVC_COIL, start);
    for (i = 0u; i < qty; i++) {
        el_svc_value_t v;
        uint8_t e;
        if (i > 0u)
            k = next_cover(m, EL_SVC_COIL, k, (uint16_t)(start + i));
        v.u = (uint32_t)((req[6u + i / 8u] >> (i % 8u)) & 1u);
        e = status_exception(el_service_write(m->order[k], &v));
        if (ex == 0u)
            ex = e;
    }
    if (ex != 0u)
        return exception(0x0Fu, ex, resp);
    resp[0] = 0x0Fu;
    put16(resp + 1, start);
    put16(resp + 3, qty);
    return 5u;
}

/* ---- 16: write multiple registers ---- */

/* Walk the entries of [start, start + qty): pass 0 checks the addresses
 * (each entry wholly inside), pass 1 the values, pass 2 writes. Returns an
 * exception code, or 0. */
static uint8_t walk_regs(const el_svc_map_t *m, const uint8_t *data, uint16_t start, uint16_t qty, uint8_t pass)
{
    uint32_t end = (uint32_t)start + qty;
    uint32_t address = start;
    uint8_t ex = 0u;
    uint16_t k = locate(m, EL_SVC_HOLDING, start);
    while (address < end) {
        const el_svc_entry_t *e;
        uint16_t regs[2], off;
        el_svc_value_t v;
        if (address != start)
            k = next_cover(m, EL_SVC_HOLDING, k, (uint16_t)address);
        if (k == NOT_FOUND)
            return EL_MB_EX_ILLEGAL_ADDRESS;
        e = at(m, k);
        if (e->address != address || address + span(e) > end)
            return EL_MB_EX_ILLEGAL_ADDRESS; /* a hole, or a cut 32-bit item */
        off = (uint16_t)(2u * (address - start));
        regs[0] = get16(data + off);
        regs[1] = span(e) == 2u ? get16(data + off + 2u) : 0u;
        address += span(e);
        if (pass == 0u)
            continue;
        if (el_service_from_regs(e->type, regs, &v) != EL_SVC_OK)
            return EL_MB_EX_ILLEGAL_VALUE;
        if (pass == 1u) {
            if (el_service_check(m->order[k], &v) != EL_SVC_OK)
                return EL_MB_EX_ILLEGAL_VALUE;
        } else {
            uint8_t e2 = status_exception(el_service_write(m->order[k], &v));
            if (ex == 0u)
                ex = e2;
        }
    }
    return ex;
}

static uint16_t write_regs(const el_svc_map_t *m, const uint8_t *req, uint16_t len, uint8_t *resp)
{
    uint16_t start, qty;
    uint8_t ex;
    if (len < 6u)
        return exception(0x10u, EL_MB_EX_ILLEGAL_VALUE, resp);
    start = get16(req + 1);
    qty = get16(req + 3);
    if (qty < 1u || qty > EL_MB_MAX_WRITE_REGS || req[5] != 2u * qty || len != 6u + req[5])
        return exception(0x10u, EL_MB_EX_ILLEGAL_VALUE, resp);
    if ((uint32_t)start + qty > 0x10000UL)
        return exception(0x10u, EL_MB_EX_ILLEGAL_ADDRESS, resp);
    ex = walk_regs(m, req + 6, start, qty, 0u);
    if (ex == 0u)
        ex = walk_regs(m, req + 6, start, qty, 1u);
    if (ex == 0u)
        ex = walk_regs(m, req + 6, start, qty, 2u);
    if (ex != 0u)
        return exception(0x10u, ex, resp);
    resp[0] = 0x10u;
    put16(resp + 1, start);
    put16(resp + 3, qty);
    return 5u;
}

/* ---- 43 / 14: read device identification ---- */

static const uint8_t id_objects[] = {EL_MB_ID_VENDOR, EL_MB_ID_PRODUCT_CODE, EL_MB_ID_REVISION,
                                     EL_MB_ID_PRODUCT_NAME, EL_MB_ID_MODEL_NAME, EL_MB_ID_PROGRAM};
#define ID_OBJECT_COUNT ((uint8_t)(sizeof id_objects / sizeof id_objects[0]))

static const char *id_string(const el_svc_map_t *m, uint8_t object)
{
    const char *s;
    switch (object) {
    case EL_MB_ID_VENDOR: s = m->vendor; break;
    case EL_MB_ID_PRODUCT_CODE:
    case EL_MB_ID_MODEL_NAME: s = m->model; break;
    case EL_MB_ID_REVISION: s = m->version; break;
    case EL_MB_ID_PRODUCT_NAME: s = m->title; break;
    case EL_MB_ID_PROGRAM: s = m->program; break;
    default: return (const char *)0;
    }
    return s != (const char *)0 ? s : "";
}

static uint16_t id_put(uint8_t *resp, uint16_t pos, uint8_t object, const char *s)
{
    uint16_t n = 0u;
    while (s[n] != '\0' && n < ID_STRING_MAX)
        n++;
    resp[pos] = object;
    resp[pos + 1u] = (uint8_t)n;
    for (pos = (uint16_t)(pos + 2u); n > 0u; n--, pos++, s++)
        resp[pos] = (uint8_t)*s;
    return pos;
}

static uint16_t device_id(const el_svc_map_t *m, const uint8_t *req, uint16_t len, uint8_t *resp)
{
    uint8_t code, object, last, i, count = 0u;
    uint16_t pos;
    if (len < 2u)
        return exception(0x2Bu, EL_MB_EX_ILLEGAL_VALUE, resp);
    if (req[1] != 0x0Eu)
        return exception(0x2Bu, EL_MB_EX_ILLEGAL_FUNCTION, resp); /* other MEI types */
    if (len != 4u || req[2] < 1u || req[2] > 4u)
        return exception(0x2Bu, EL_MB_EX_ILLEGAL_VALUE, resp);
    code = req[2];
    object = req[3];
    if (code == 4u && id_string(m, object) == (const char *)0)
        return exception(0x2Bu, EL_MB_EX_ILLEGAL_ADDRESS, resp);
    resp[0] = 0x2Bu;
    resp[1] = 0x0Eu;
    resp[2] = code;
    resp[3] = 0x83u; /* basic, regular and extended; stream and individual access */
    resp[4] = 0x00u; /* more follows */
    resp[5] = 0x00u; /* next object id */
    pos = 7u;
    if (code == 4u) {
        resp[6] = 1u;
        return id_put(resp, pos, object, id_string(m, object));
    }
    last = code == 1u ? EL_MB_ID_REVISION : (code == 2u ? 0x7Fu : 0xFFu);
    /* Stream access from `object`; an unknown object restarts at the first. */
    for (i = 0u; i < ID_OBJECT_COUNT && id_objects[i] != object; i++) {
    }
    if (i == ID_OBJECT_COUNT || object > last)
        i = 0u;
    for (; i < ID_OBJECT_COUNT && id_objects[i] <= last; i++) {
        const char *s = id_string(m, id_objects[i]);
        uint16_t n = 0u;
        while (s[n] != '\0' && n < ID_STRING_MAX)
            n++;
        if (pos + 2u + n > EL_MB_PDU_MAX) {
            resp[4] = 0xFFu;
            resp[5] = id_objects[i];
            break;
        }
        pos = id_put(resp, pos, id_objects[i], s);
        count++;
    }
    resp[6] = count;
    return pos;
}

/* ---- the PDU dispatcher ---- */

#if defined(EL_ROUND_SLAVE)
/* A slave of a Modbus round (docs/distribution.md) answers the round's sync
 * and function-23 slot first (the node's generated el_link.c defines it,
 * and the build defines EL_ROUND_SLAVE; 0xFFFF: not the round's). */
uint16_t el_mb_round_pdu(const uint8_t *req, uint16_t len, uint8_t *resp, bool broadcast);
#endif

uint16_t el_mb_pdu(const uint8_t *req, uint16_t len, uint8_t *resp, bool broadcast)
{
    const el_svc_map_t *m = el_service_map();
    uint8_t fc;
    if (req == (const uint8_t *)0 || resp == (uint8_t *)0 || len == 0u || len > EL_MB_PDU_MAX)
        return 0u;
#if defined(EL_ROUND_SLAVE)
    {
        uint16_t answered = el_mb_round_pdu(req, len, resp, broadcast);
        if (answered != 0xFFFFu)
            return answered;
    }
#endif
    fc = req[0];
    switch (fc) {
    case 0x05u:
    case 0x06u:
    case 0x0Fu:
    case 0x10u: {
        /* A broadcast executes the write and is never answered, not even
         * with an exception. */
        uint16_t r = 0u;
        if (m != (const el_svc_map_t *)0)
            r = fc == 0x05u ? write_coil(m, req, len, resp)
                : fc == 0x06u ? write_reg(m, req, len, resp)
                : fc == 0x0Fu ? write_coils(m, req, len, resp) : write_regs(m, req, len, resp);
        return broadcast ? 0u : r;
    }
    default:
        break;
    }
    if (broadcast || m == (const el_svc_map_t *)0)
        return 0u; /* reads are never broadcast: no effect, no reply */
    switch (fc) {
    case 0x01u:
    case 0x02u: return read_bits(m, fc, req, len, resp);
    case 0x03u:
    case 0x04u: return read_regs(m, fc, req, len, resp);
    case 0x2Bu: return device_id(m, req, len, resp);
    default: return exception(fc, EL_MB_EX_ILLEGAL_FUNCTION, resp);
    }
}

/* ---- RTU ---- */

void el_mb_rtu_init(el_mb_rtu_t *rtu, uint8_t unit, bool early)
{
    rtu->len = 0u;
    rtu->crc = EL_CRC16_INIT;
    rtu->unit = unit;
    rtu->flags = early ? EL_MB_RTU_EARLY : 0u;
    rtu->frames = 0u;
    rtu->bad_frames = 0u;
}

/* The length of a request of this function code, from its first `len`
 * bytes: 0 while unknown yet, 0xFFFF for function codes of other lengths. */
static uint16_t request_length(const uint8_t *buf, uint16_t len)
{
    uint8_t fc = buf[1];
    if (fc >= 0x01u && fc <= 0x06u)
        return 8u;
    if (fc == 0x0Fu || fc == 0x10u)
        return len >= 7u ? (uint16_t)(9u + buf[6]) : 0u;
    if (fc == 0x2Bu)
        return len >= 3u ? (buf[2] == 0x0Eu ? 7u : 0xFFFFu) : 0u;
    if (fc == 0x17u) /* a round's slot (docs/distribution.md) */
        return len >= 11u ? (uint16_t)(13u + buf[10]) : 0u;
    return 0xFFFFu;
}

bool el_mb_rtu_byte(el_mb_rtu_t *rtu, uint8_t byte)
{
    uint16_t want;
    if ((rtu->flags & EL_MB_RTU_READY) != 0u)
        return false; /* a frame waits for its reply */
    if (rtu->len >= EL_MB_RTU_ADU_MAX) {
        rtu->flags |= EL_MB_RTU_OVERFLOW;
        return false;
    }
    rtu->buf[rtu->len++] = byte;
    rtu->crc = el_crc16_fast_byte(rtu->crc, byte);
    if ((rtu->flags & (EL_MB_RTU_EARLY | EL_MB_RTU_OVERFLOW)) != EL_MB_RTU_EARLY || rtu->len < 4u || rtu->crc != 0u)
        return false;
    want = request_length(rtu->buf, rtu->len);
    if (want != 0xFFFFu && want != rtu->len)
        return false;
    rtu->flags |= EL_MB_RTU_READY;
    return true;
}

bool el_mb_rtu_silence(el_mb_rtu_t *rtu)
{
    if ((rtu->flags & EL_MB_RTU_READY) != 0u)
        return true;
    if (rtu->len == 0u && (rtu->flags & EL_MB_RTU_OVERFLOW) == 0u)
        return false;
    rtu->flags |= EL_MB_RTU_READY;
    return true;
}

uint16_t el_mb_rtu_reply(el_mb_rtu_t *rtu)
{
    uint16_t n = rtu->len, r, crc;
    bool good = (rtu->flags & EL_MB_RTU_OVERFLOW) == 0u && n >= 4u && rtu->crc == 0u;
    uint8_t unit;
    rtu->len = 0u;
    rtu->crc = EL_CRC16_INIT;
    rtu->flags &= EL_MB_RTU_EARLY;
    if (!good) {
        if (n > 0u)
            rtu->bad_frames++;
        return 0u;
    }
    unit = rtu->buf[0];
    if (unit != rtu->unit && unit != 0u)
        return 0u; /* for another slave */
    rtu->frames++;
    r = el_mb_pdu(rtu->buf + 1, (uint16_t)(n - 3u), rtu->buf + 1, unit == 0u);
    if (r == 0u)
        return 0u;
    crc = el_crc16_fast(EL_CRC16_INIT, rtu->buf, (uint16_t)(r + 1u));
    rtu->buf[r + 1u] = (uint8_t)(crc & 0xFFu);
    rtu->buf[r + 2u] = (uint8_t)(crc >> 8);
    return (uint16_t)(r + 3u);
}

void el_mb_rtu_poll(el_mb_rtu_t *rtu, const el_mb_rtu_port_t *port)
{
    uint16_t budget;
    for (budget = 0u; budget < 2u * EL_MB_RTU_ADU_MAX; budget++) {
        int16_t c = port->getc();
        bool ready;
        if (c == EL_MB_NONE)
            break;
        if (c == EL_MB_SILENCE)
            ready = el_mb_rtu_silence(rtu);
        else if (c >= 0 && c <= 0xFF)
            ready = el_mb_rtu_byte(rtu, (uint8_t)c);
        else
            break;
        if (ready) {
            uint16_t n = el_mb_rtu_reply(rtu);
            if (n > 0u)
                port->send(rtu->buf, n);
        }
    }
}

/* ---- TCP ---- */

int16_t el_mb_tcp_adu_length(const uint8_t *head, uint16_t avail)
{
    uint16_t length;
    if (avail < EL_MB_MBAP)
        return 0;
    if (get16(head + 2) != 0u)
        return EL_MB_TCP_BAD;
    length = get16(head + 4); /* unit id + PDU */
    if (length < 2u || length > EL_MB_PDU_MAX + 1u)
        return EL_MB_TCP_BAD;
    return (int16_t)(6u + length);
}

uint16_t el_mb_tcp_reply(uint8_t *adu, uint16_t len)
{
    int16_t want = el_mb_tcp_adu_length(adu, len);
    uint16_t r;
    if (want <= 0 || (uint16_t)want != len)
        return 0u;
    r = el_mb_pdu(adu + EL_MB_MBAP, (uint16_t)(len - EL_MB_MBAP), adu + EL_MB_MBAP, false);
    if (r == 0u)
        return 0u;
    put16(adu + 4, (uint16_t)(r + 1u));
    return (uint16_t)(EL_MB_MBAP + r);
}

void el_mb_tcp_poll(const el_mb_tcp_port_t *port, uint8_t *buf)
{
    uint8_t conn, k;
    for (conn = 0u; conn < port->conns; conn++) {
        for (k = 0u; k < 8u; k++) {
            uint16_t got = port->peek(conn, buf, EL_MB_MBAP), r;
            int16_t want = el_mb_tcp_adu_length(buf, got);
            if (want == 0)
                break;
            if (want < 0) {
                port->close(conn);
                break;
            }
            if (port->peek(conn, buf, (uint16_t)want) < (uint16_t)want)
                break; /* the rest of the request is still on its way */
            port->consume(conn, (uint16_t)want);
            r = el_mb_tcp_reply(buf, (uint16_t)want);
            if (r > 0u && !port->send(conn, buf, r))
                break;
        }
    }
}
