/* EasyLab PIC18 board: 64-bit integer arithmetic on 32-bit words (see
 * el_pic18_w64.h). Portable C; compiled by sdcc for the PIC18 and by gcc
 * for the lowering's own tests (tests/pic18/test_lower64.py). */
#include "el_pic18_w64.h"

#define SIGN(a) (((a)->hi & 0x80000000UL) != 0u)

void el_w64_from_i32(el_w64_t *r, int32_t v)
{
    r->lo = (uint32_t)v;
    r->hi = v < 0 ? 0xFFFFFFFFUL : 0u;
}

void el_w64_from_u32(el_w64_t *r, uint32_t v)
{
    r->lo = v;
    r->hi = 0u;
}

void el_w64_add(el_w64_t *r, const el_w64_t *a, const el_w64_t *b)
{
    uint32_t lo = a->lo + b->lo;
    r->hi = a->hi + b->hi + (lo < a->lo ? 1u : 0u);
    r->lo = lo;
}

void el_w64_sub(el_w64_t *r, const el_w64_t *a, const el_w64_t *b)
{
    uint32_t lo = a->lo - b->lo;
    r->hi = a->hi - b->hi - (a->lo < b->lo ? 1u : 0u);
    r->lo = lo;
}

void el_w64_neg(el_w64_t *r, const el_w64_t *a)
{
    uint32_t lo = 0u - a->lo;
    r->hi = 0u - a->hi - (a->lo != 0u ? 1u : 0u);
    r->lo = lo;
}

void el_w64_not(el_w64_t *r, const el_w64_t *a)
{
    r->lo = ~a->lo;
    r->hi = ~a->hi;
}

void el_w64_and(el_w64_t *r, const el_w64_t *a, const el_w64_t *b)
{
    r->lo = a->lo & b->lo;
    r->hi = a->hi & b->hi;
}

void el_w64_or(el_w64_t *r, const el_w64_t *a, const el_w64_t *b)
{
    r->lo = a->lo | b->lo;
    r->hi = a->hi | b->hi;
}

void el_w64_xor(el_w64_t *r, const el_w64_t *a, const el_w64_t *b)
{
    r->lo = a->lo ^ b->lo;
    r->hi = a->hi ^ b->hi;
}

void el_w64_mul(el_w64_t *r, const el_w64_t *a, const el_w64_t *b)
{
    /* The low 64 bits of the product: the 32 x 32 bit product of the low
     * words from four 16 x 16 bit ones, plus the cross terms' low words. */
    uint16_t a0 = (uint16_t)a->lo, a1 = (uint16_t)(a->lo >> 16);
    uint16_t b0 = (uint16_t)b->lo, b1 = (uint16_t)(b->lo >> 16);
    uint32_t p00 = (uint32_t)a0 * b0, p01 = (uint32_t)a0 * b1;
    uint32_t p10 = (uint32_t)a1 * b0, p11 = (uint32_t)a1 * b1;
    uint32_t mid = (p00 >> 16) + (p01 & 0xFFFFu) + (p10 & 0xFFFFu);
    uint32_t hi = p11 + (p01 >> 16) + (p10 >> 16) + (mid >> 16) + a->lo * b->hi + a->hi * b->lo;
    r->lo = (p00 & 0xFFFFu) | (mid << 16);
    r->hi = hi;
}

/* Unsigned division with remainder: 64 steps of shift and subtract, or
 * the 32-bit division when both fit in 32 bits. */
static void divmod_u(el_w64_t *q, el_w64_t *rem, const el_w64_t *a, const el_w64_t *b)
{
    uint32_t qlo = 0u, qhi = 0u, rlo = 0u, rhi = 0u;
    uint32_t nlo = a->lo, nhi = a->hi;
    uint8_t i;
    if ((b->lo | b->hi) == 0u) {
        q->lo = q->hi = rem->lo = rem->hi = 0u;
        return;
    }
    if ((nhi | b->hi) == 0u) {
        q->lo = nlo / b->lo;
        rem->lo = nlo % b->lo;
        q->hi = rem->hi = 0u;
        return;
    }
    for (i = 0u; i < 64u; i++) {
        rhi = (rhi << 1) | (rlo >> 31);
        rlo = (rlo << 1) | (nhi >> 31);
        nhi = (nhi << 1) | (nlo >> 31);
        nlo <<= 1;
        qhi = (qhi << 1) | (qlo >> 31);
        qlo <<= 1;
        if (rhi > b->hi || (rhi == b->hi && rlo >= b->lo)) {
            uint32_t borrow = rlo < b->lo ? 1u : 0u;
            rlo -= b->lo;
            rhi = rhi - b->hi - borrow;
            qlo |= 1u;
        }
    }
    q->lo = qlo;
    q->hi = qhi;
    rem->lo = rlo;
    rem->hi = rhi;
}

void el_w64_divu(el_w64_t *r, const el_w64_t *a, const el_w64_t *b)
{
    el_w64_t rem;
    divmod_u(r, &rem, a, b);
}

void el_w64_modu(el_w64_t *r, const el_w64_t *a, const el_w64_t *b)
{
    el_w64_t q;
    divmod_u(&q, r, a, b);
}

/* Signed division: on the magnitudes; the quotient is negative when the
 * signs differ, the remainder has the dividend's sign. */
static void divmod_s(el_w64_t *q, el_w64_t *rem, const el_w64_t *a, const el_w64_t *b)
{
    el_w64_t ua, ub;
    uint8_t na = SIGN(a) ? 1u : 0u, nb = SIGN(b) ? 1u : 0u;
    /* Word by word: sdcc 4.2 copies a struct with a __memcpy it does not declare. */
    if (na) {
        el_w64_neg(&ua, a);
    } else {
        ua.lo = a->lo;
        ua.hi = a->hi;
    }
    if (nb) {
        el_w64_neg(&ub, b);
    } else {
        ub.lo = b->lo;
        ub.hi = b->hi;
    }
    divmod_u(q, rem, &ua, &ub);
    if (na != nb) {
        el_w64_neg(q, q);
    }
    if (na) {
        el_w64_neg(rem, rem);
    }
}

void el_w64_divs(el_w64_t *r, const el_w64_t *a, const el_w64_t *b)
{
    el_w64_t rem;
    divmod_s(r, &rem, a, b);
}

void el_w64_mods(el_w64_t *r, const el_w64_t *a, const el_w64_t *b)
{
    el_w64_t q;
    divmod_s(&q, r, a, b);
}

void el_w64_shl(el_w64_t *r, const el_w64_t *a, uint8_t n)
{
    uint32_t lo = a->lo, hi = a->hi;
    if (n >= 64u) {
        lo = hi = 0u;
    } else if (n >= 32u) {
        hi = lo << (n - 32u);
        lo = 0u;
    } else if (n != 0u) {
        hi = (hi << n) | (lo >> (32u - n));
        lo <<= n;
    }
    r->lo = lo;
    r->hi = hi;
}

static void shift_right(el_w64_t *r, const el_w64_t *a, uint8_t n, uint32_t fill)
{
    uint32_t lo = a->lo, hi = a->hi;
    if (n >= 64u) {
        lo = hi = fill;
    } else if (n >= 32u) {
        lo = n == 32u ? hi : (hi >> (n - 32u)) | (fill << (64u - n));
        hi = fill;
    } else if (n != 0u) {
        lo = (lo >> n) | (hi << (32u - n));
        hi = (hi >> n) | (fill << (32u - n));
    }
    r->lo = lo;
    r->hi = hi;
}

void el_w64_shrs(el_w64_t *r, const el_w64_t *a, uint8_t n)
{
    shift_right(r, a, n, SIGN(a) ? 0xFFFFFFFFUL : 0u);
}

void el_w64_shru(el_w64_t *r, const el_w64_t *a, uint8_t n)
{
    shift_right(r, a, n, 0u);
}

int8_t el_w64_cmpu(const el_w64_t *a, const el_w64_t *b)
{
    if (a->hi != b->hi) {
        return a->hi < b->hi ? (int8_t)-1 : (int8_t)1;
    }
    if (a->lo != b->lo) {
        return a->lo < b->lo ? (int8_t)-1 : (int8_t)1;
    }
    return 0;
}

int8_t el_w64_cmps(const el_w64_t *a, const el_w64_t *b)
{
    uint8_t na = SIGN(a) ? 1u : 0u, nb = SIGN(b) ? 1u : 0u;
    if (na != nb) {
        return na ? (int8_t)-1 : (int8_t)1;
    }
    return el_w64_cmpu(a, b);
}

/* ---- floats: a magnitude below 2^24 converts exactly through uint32;
 * a larger one is rounded to 24 bits here (to nearest, ties to even) and
 * scaled by a power of two, which is exact. */

static float scale2(float f, uint8_t e)
{
    while (e >= 16u) {
        f *= 65536.0f;
        e = (uint8_t)(e - 16u);
    }
    while (e > 0u) {
        f *= 2.0f;
        e--;
    }
    return f;
}

float el_w64_to_f32u(const el_w64_t *a)
{
    uint32_t hi = a->hi, lo = a->lo;
    uint32_t last = 0u, sticky = 0u; /* the last bit shifted out; any other */
    uint8_t shift = 0u;
    while (hi != 0u || lo >= 0x01000000UL) {
        sticky |= last;
        last = lo & 1u;
        lo = (lo >> 1) | (hi << 31);
        hi >>= 1;
        shift++;
    }
    if (last != 0u && (sticky != 0u || (lo & 1u) != 0u)) {
        lo++; /* at most 2^24: still exact as a float */
    }
    return scale2((float)lo, shift);
}

float el_w64_to_f32s(const el_w64_t *a)
{
    el_w64_t m;
    if (!SIGN(a)) {
        return el_w64_to_f32u(a);
    }
    el_w64_neg(&m, a); /* INT64_MIN stays 2^63 as an unsigned magnitude */
    return -el_w64_to_f32u(&m);
}

void el_w64_from_f32u(el_w64_t *r, float v)
{
    uint8_t e = 0u;
    r->lo = r->hi = 0u;
    if (!(v >= 1.0f)) { /* below 1, negative (undefined in C) or NaN */
        return;
    }
    /* Halving is exact; from 2^32 on a float holds an integer. */
    while (v >= 4294967296.0f && e < 64u) {
        v *= 0.5f;
        e++;
    }
    r->lo = (uint32_t)v;
    el_w64_shl(r, r, e);
}

void el_w64_from_f32s(el_w64_t *r, float v)
{
    if (v < 0.0f) {
        el_w64_from_f32u(r, -v);
        el_w64_neg(r, r);
    } else {
        el_w64_from_f32u(r, v);
    }
}
