/* EasyLab runtime: the service map's local API and value conversions (see
 * el_service.h). */
#include "el_service.h"
#include "el_model.h"
#include "el_persist.h"

static const el_svc_map_t *svc_map;

typedef union {
    float f;
    uint32_t u;
} el_f32_bits_t;

static float f32_of_bits(uint32_t bits)
{
    el_f32_bits_t x;
    x.u = bits;
    return x.f;
}

static uint32_t bits_of_f32(float f)
{
    el_f32_bits_t x;
    x.f = f;
    return x.u;
}

/* A 32-bit pattern as a signed value, without implementation-defined
 * conversions. */
static int32_t i32_of_bits(uint32_t u)
{
    if (u <= 0x7FFFFFFFUL)
        return (int32_t)u;
    return (int32_t)(-(int32_t)(~u) - 1);
}

static bool finite_f32(float f)
{
    /* NaN and the infinities have every exponent bit set. */
    return (bits_of_f32(f) & 0x7F800000UL) != 0x7F800000UL;
}

void el_service_init(const el_svc_map_t *map)
{
    svc_map = map;
    el_persist_load(map);
}

const el_svc_map_t *el_service_map(void)
{
    return svc_map;
}

uint16_t el_service_count(void)
{
    return svc_map != (const el_svc_map_t *)0 ? svc_map->count : 0u;
}

uint16_t el_service_find(const char *name)
{
    uint16_t id;
    if (svc_map == (const el_svc_map_t *)0 || name == (const char *)0)
        return EL_SVC_NONE;
    for (id = 0u; id < svc_map->count; id++) {
        const char *a = svc_map->entries[id].name, *b = name;
        while (*a != '\0' && *a == *b) {
            a++;
            b++;
        }
        if (*a == '\0' && *b == '\0')
            return id;
    }
    return EL_SVC_NONE;
}

const el_svc_entry_t *el_service_entry(uint16_t id)
{
    if (svc_map == (const el_svc_map_t *)0 || id >= svc_map->count)
        return (const el_svc_entry_t *)0;
    return &svc_map->entries[id];
}

uint8_t el_service_regs(uint8_t type)
{
    switch (type) {
    case EL_T_BOOL: return 0u;
    case EL_T_I8:
    case EL_T_U8:
    case EL_T_I16:
    case EL_T_U16: return 1u;
    default: return 2u;
    }
}

el_svc_status_t el_service_get(uint16_t id, el_svc_value_t *value)
{
    const el_svc_entry_t *e = el_service_entry(id);
    if (e == (const el_svc_entry_t *)0 || value == (el_svc_value_t *)0)
        return EL_SVC_NO_ITEM;
    value->u = 0u;
    switch (e->type) {
    case EL_T_BOOL: value->u = *(const bool *)e->addr ? 1u : 0u; break;
    case EL_T_I8: value->i = *(const int8_t *)e->addr; break;
    case EL_T_U8: value->u = *(const uint8_t *)e->addr; break;
    case EL_T_I16: value->i = *(const int16_t *)e->addr; break;
    case EL_T_U16: value->u = *(const uint16_t *)e->addr; break;
    case EL_T_I32: value->i = *(const int32_t *)e->addr; break;
    case EL_T_U32:
    case EL_T_TIME: value->u = *(const uint32_t *)e->addr; break;
    case EL_T_F32: value->f = *(const float *)e->addr; break;
    default: return EL_SVC_NO_ITEM;
    }
    return EL_SVC_OK;
}

el_svc_status_t el_service_check(uint16_t id, const el_svc_value_t *value)
{
    const el_svc_entry_t *e = el_service_entry(id);
    bool ranged;
    if (e == (const el_svc_entry_t *)0 || value == (const el_svc_value_t *)0)
        return EL_SVC_NO_ITEM;
    ranged = (e->flags & EL_SVC_F_RANGE) != 0u;
    switch (e->type) {
    case EL_T_BOOL:
        return value->u <= 1u ? EL_SVC_OK : EL_SVC_BAD_VALUE;
    case EL_T_I8:
    case EL_T_I16:
    case EL_T_I32: {
        int32_t lo = e->type == EL_T_I8 ? -128L : (e->type == EL_T_I16 ? -32768L : (int32_t)(-2147483647L - 1L));
        int32_t hi = e->type == EL_T_I8 ? 127L : (e->type == EL_T_I16 ? 32767L : 2147483647L);
        if (ranged) {
            lo = i32_of_bits(e->lo);
            hi = i32_of_bits(e->hi);
        }
        return value->i >= lo && value->i <= hi ? EL_SVC_OK : EL_SVC_BAD_VALUE;
    }
    case EL_T_U8:
    case EL_T_U16:
    case EL_T_U32:
    case EL_T_TIME: {
        uint32_t lo = 0u;
        uint32_t hi = e->type == EL_T_U8 ? 255UL : (e->type == EL_T_U16 ? 65535UL : 0xFFFFFFFFUL);
        if (ranged) {
            lo = e->lo;
            hi = e->hi;
        }
        return value->u >= lo && value->u <= hi ? EL_SVC_OK : EL_SVC_BAD_VALUE;
    }
    case EL_T_F32:
        if (!finite_f32(value->f))
            return EL_SVC_BAD_VALUE;
        if (ranged && (value->f < f32_of_bits(e->lo) || value->f > f32_of_bits(e->hi)))
            return EL_SVC_BAD_VALUE;
        return EL_SVC_OK;
    default:
        return EL_SVC_NO_ITEM;
    }
}

el_svc_status_t el_service_write(uint16_t id, const el_svc_value_t *value)
{
    const el_svc_entry_t *e;
    el_svc_status_t st = el_service_check(id, value);
    if (st != EL_SVC_OK)
        return st;
    e = &svc_map->entries[id];
    switch (e->type) {
    case EL_T_BOOL: *(bool *)e->addr = value->u != 0u; break;
    case EL_T_I8: *(int8_t *)e->addr = (int8_t)value->i; break;
    case EL_T_U8: *(uint8_t *)e->addr = (uint8_t)value->u; break;
    case EL_T_I16: *(int16_t *)e->addr = (int16_t)value->i; break;
    case EL_T_U16: *(uint16_t *)e->addr = (uint16_t)value->u; break;
    case EL_T_I32: *(int32_t *)e->addr = value->i; break;
    case EL_T_U32:
    case EL_T_TIME: *(uint32_t *)e->addr = value->u; break;
    case EL_T_F32: *(float *)e->addr = value->f; break;
    default: return EL_SVC_NO_ITEM;
    }
    if ((e->flags & EL_SVC_F_PERSIST) != 0u && !el_persist_store(svc_map, id, el_service_bits(e->type, value)))
        return EL_SVC_STORAGE;
    return EL_SVC_OK;
}

el_svc_status_t el_service_set(uint16_t id, const el_svc_value_t *value)
{
    const el_svc_entry_t *e = el_service_entry(id);
    if (e == (const el_svc_entry_t *)0)
        return EL_SVC_NO_ITEM;
    if ((e->flags & EL_SVC_F_RW) == 0u)
        return EL_SVC_READ_ONLY;
    return el_service_write(id, value);
}

uint32_t el_service_bits(uint8_t type, const el_svc_value_t *value)
{
    switch (type) {
    case EL_T_I8:
    case EL_T_I16:
    case EL_T_I32: return (uint32_t)value->i; /* modulo 2^32: two's complement */
    case EL_T_F32: return bits_of_f32(value->f);
    default: return value->u;
    }
}

void el_service_from_bits(uint8_t type, uint32_t bits, el_svc_value_t *value)
{
    switch (type) {
    case EL_T_I8:
    case EL_T_I16:
    case EL_T_I32: value->i = i32_of_bits(bits); break;
    case EL_T_F32: value->f = f32_of_bits(bits); break;
    default: value->u = bits; break;
    }
}

void el_service_to_regs(uint8_t type, const el_svc_value_t *value, uint16_t regs[2])
{
    uint32_t bits = el_service_bits(type, value);
    if (el_service_regs(type) == 2u) {
        regs[0] = (uint16_t)(bits >> 16);
        regs[1] = (uint16_t)(bits & 0xFFFFu);
    } else {
        regs[0] = (uint16_t)(bits & 0xFFFFu); /* int8/int16 sign-extended: the low half */
        regs[1] = 0u;
    }
}

el_svc_status_t el_service_from_regs(uint8_t type, const uint16_t regs[2], el_svc_value_t *value)
{
    int32_t s = i32_of_bits(regs[0] >= 0x8000u ? 0xFFFF0000UL | regs[0] : (uint32_t)regs[0]);
    switch (type) {
    case EL_T_BOOL:
        if (regs[0] > 1u)
            return EL_SVC_BAD_VALUE;
        value->u = regs[0];
        return EL_SVC_OK;
    case EL_T_I8:
        if (s < -128L || s > 127L)
            return EL_SVC_BAD_VALUE;
        value->i = s;
        return EL_SVC_OK;
    case EL_T_U8:
        if (regs[0] > 255u)
            return EL_SVC_BAD_VALUE;
        value->u = regs[0];
        return EL_SVC_OK;
    case EL_T_I16:
        value->i = s;
        return EL_SVC_OK;
    case EL_T_U16:
        value->u = regs[0];
        return EL_SVC_OK;
    case EL_T_F32:
        value->f = f32_of_bits(((uint32_t)regs[0] << 16) | regs[1]);
        return finite_f32(value->f) ? EL_SVC_OK : EL_SVC_BAD_VALUE;
    default: /* int32, uint32, time */
        el_service_from_bits(type, ((uint32_t)regs[0] << 16) | regs[1], value);
        return EL_SVC_OK;
    }
}
