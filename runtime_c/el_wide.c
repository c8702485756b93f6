/* EasyLab runtime: 64-bit two's complement arithmetic in two 32-bit words,
 * for compilers without a 64-bit integer type (el_wide.h). Every operation
 * gives what el_wide.h's int64_t form gives: sums, differences, products
 * and quotients saturate at the 64-bit range, quotients truncate toward
 * zero. Nothing here needs more than uint32_t, and no product is formed
 * in (possibly 16-bit) int. */
#include "el_wide.h"

#define W64_SIGN 0x80000000UL

/* The end of the range on a side: INT64_MIN or INT64_MAX. */
static void w64_saturate(el_w64_t *w, bool negative)
{
    w->lo = negative ? 0UL : 0xFFFFFFFFUL;
    w->hi = negative ? W64_SIGN : 0x7FFFFFFFUL;
}

static void w64_negate(el_w64_t *w)
{
    w->lo = ~w->lo + 1UL;
    w->hi = ~w->hi + (w->lo == 0UL ? 1UL : 0UL);
}

/* A sum overflows when both operands have one sign and the sum the other. */
static void w64_add(el_w64_t *w, const el_w64_t *x)
{
    uint32_t lo = w->lo + x->lo;
    uint32_t sign = w->hi & W64_SIGN;
    bool same = sign == (x->hi & W64_SIGN); /* before w changes: x may be w */
    w->hi = w->hi + x->hi + (lo < w->lo ? 1UL : 0UL);
    w->lo = lo;
    if (same && sign != (w->hi & W64_SIGN)) {
        w64_saturate(w, sign != 0UL);
    }
}

/* A difference overflows when the operands' signs differ and the result's
 * is not the minuend's. */
static void w64_sub(el_w64_t *w, const el_w64_t *x)
{
    uint32_t borrow = w->lo < x->lo ? 1UL : 0UL;
    uint32_t sign = w->hi & W64_SIGN;
    bool differ = sign != (x->hi & W64_SIGN); /* before w changes: x may be w */
    w->lo = w->lo - x->lo;
    w->hi = w->hi - x->hi - borrow;
    if (differ && sign != (w->hi & W64_SIGN)) {
        w64_saturate(w, sign != 0UL);
    }
}

/* w * b for a multiplier that fits 32 bits, given as its magnitude and
 * sign (every product of std's actors: by a gain, by a model value),
 * saturated. On w's magnitude a = ah:al, a * b = ah * b * 2^32 + al * b:
 * ah * b must fit 32 bits, and the high word of the sum must not carry
 * nor reach the sign bit (but for -2^63 itself). al * b comes from 16-bit
 * halves (a1:a0 times b1:b0), each partial product fitting a uint32_t.
 * Few locals: the proxy's 8051 keeps them on a stack of some 200 bytes. */
static void w64_mul32(el_w64_t *w, uint32_t b, bool negative)
{
    uint32_t cross, hi, lo, mid;

    if ((w->hi & W64_SIGN) != 0UL) {
        w64_negate(w);
        negative = !negative;
    }
    if (w->hi != 0UL && b > 0xFFFFFFFFUL / w->hi) {
        w64_saturate(w, negative);
        return;
    }
    cross = w->hi * b;
    lo = (w->lo & 0xFFFFUL) * (b & 0xFFFFUL);               /* a0 b0 */
    mid = (w->lo >> 16) * (b & 0xFFFFUL);                   /* a1 b0 */
    hi = (w->lo >> 16) * (b >> 16) + (mid >> 16);           /* a1 b1 */
    mid = (mid & 0xFFFFUL) + (lo >> 16);
    w->lo = (w->lo & 0xFFFFUL) * (b >> 16);                 /* a0 b1, held in place */
    mid += w->lo & 0xFFFFUL;
    hi += (w->lo >> 16) + (mid >> 16);                      /* al * b < 2^64: no carry */
    w->lo = (lo & 0xFFFFUL) | (mid << 16);
    w->hi = cross + hi;
    if (w->hi < cross || ((w->hi & W64_SIGN) != 0UL && !(negative && w->hi == W64_SIGN && w->lo == 0UL))) {
        w64_saturate(w, negative);
        return;
    }
    if (negative) {
        w64_negate(w);
    }
}

/* w * x, saturated: one of the magnitudes must be below 2^32 (else the
 * product is at least 2^64), and multiplies the other. */
static void w64_mul(el_w64_t *w, const el_w64_t *x)
{
    el_w64_t b;
    bool negative;

    b.lo = x->lo;
    b.hi = x->hi;
    negative = (b.hi & W64_SIGN) != 0UL;
    if (negative) {
        w64_negate(&b);
    }
    if (b.hi != 0UL) { /* |x| >= 2^32: x times w's magnitude */
        negative = (w->hi & W64_SIGN) != 0UL;
        b.lo = w->lo;
        b.hi = w->hi;
        w->lo = x->lo;
        w->hi = x->hi;
        if (negative) {
            w64_negate(&b);
        }
        if (b.hi != 0UL) {
            w64_saturate(w, ((w->hi & W64_SIGN) != 0UL) != negative);
            return;
        }
    }
    w64_mul32(w, b.lo, negative);
}

/* Unsigned 64-bit division (n = n / d, d != 0), restoring division bit by
 * bit: the dividend shifts into the remainder and the quotient's bits into
 * the dividend's place. 32 steps when both fit 32 bits. No library calls
 * and few locals: the proxy's 8051 has a stack of some 200 bytes. */
static void w64_divu(el_w64_t *n, const el_w64_t *d)
{
    el_w64_t r;
    uint8_t bit;

    r.lo = r.hi = 0UL;
    if (n->hi == 0UL && d->hi == 0UL) {
        for (bit = 0u; bit < 32u; bit++) {
            r.lo = (r.lo << 1) | (n->lo >> 31);
            n->lo <<= 1;
            if (r.lo >= d->lo) {
                r.lo -= d->lo;
                n->lo |= 1UL;
            }
        }
        return;
    }
    for (bit = 0u; bit < 64u; bit++) {
        r.hi = (r.hi << 1) | (r.lo >> 31);
        r.lo = (r.lo << 1) | (n->hi >> 31);
        n->hi = (n->hi << 1) | (n->lo >> 31);
        n->lo <<= 1;
        if (r.hi > d->hi || (r.hi == d->hi && r.lo >= d->lo)) {
            r.hi = r.hi - d->hi - (r.lo < d->lo ? 1UL : 0UL);
            r.lo -= d->lo;
            n->lo |= 1UL;
        }
    }
}

/* w / d for a divisor that fits 32 bits, given as its magnitude and sign:
 * every division of std's actors (by 1000, by a count, by a model value).
 * The dividend's words are held in locals (fewer reads through pointers)
 * and the remainder needs 33 bits, kept as `carry` and 32. */
static void w64_div32(el_w64_t *w, uint32_t d, bool d_negative)
{
    uint32_t hi, lo, r = 0UL;
    uint8_t bit, carry;
    bool negative = d_negative;

    if (d == 0UL) {
        w->lo = w->hi = 0UL;
        return;
    }
    if ((w->hi & W64_SIGN) != 0UL) {
        w64_negate(w);
        negative = !negative;
    }
    hi = w->hi;
    lo = w->lo;
    bit = 0u;
    if (hi == 0UL) { /* the first 32 steps shift zeros: skip them */
        hi = lo;
        lo = 0UL;
        bit = 32u;
    }
    for (; bit < 64u; bit++) {
        carry = (uint8_t)(r >> 31);
        r = (r << 1) | (hi >> 31);
        hi = (hi << 1) | (lo >> 31);
        lo <<= 1;
        if (carry != 0u || r >= d) {
            r -= d;
            lo |= 1UL;
        }
    }
    w->hi = hi;
    w->lo = lo;
    if (negative) {
        w64_negate(w);
    } else if ((hi & W64_SIGN) != 0UL) { /* -2^63 / -1 */
        w64_saturate(w, false);
    }
}

static void w64_div(el_w64_t *w, const el_w64_t *x)
{
    el_w64_t d;
    bool negative = false;

    d.lo = x->lo;
    d.hi = x->hi;

    if (d.lo == 0UL && d.hi == 0UL) {
        w->lo = w->hi = 0UL;
        return;
    }
    if ((w->hi & W64_SIGN) != 0UL) {
        w64_negate(w);
        negative = true;
    }
    if ((d.hi & W64_SIGN) != 0UL) {
        w64_negate(&d);
        negative = !negative;
    }
    w64_divu(w, &d);
    if (negative) {
        w64_negate(w);
    } else if ((w->hi & W64_SIGN) != 0UL) { /* -2^63 / -1 */
        w64_saturate(w, false);
    }
}

void el_w64_set_i32(el_w64_t *w, int32_t v)
{
    w->lo = (uint32_t)v;
    w->hi = v < 0 ? 0xFFFFFFFFUL : 0UL;
}

void el_w64_set_u32(el_w64_t *w, uint32_t v)
{
    w->lo = v;
    w->hi = 0UL;
}

/* Toward zero; beyond the range: the range's end; NaN: 0. A float at or
 * above 2^32 is a whole number whose 24 significant bits split exactly
 * into the two words. NaN shows in the bits (IEEE 754 single: every
 * exponent bit set and a fraction): a compiler may fold `v != v`. */
void el_w64_set_f32(el_w64_t *w, float v)
{
    union {
        float f;
        uint32_t u;
    } bits;
    bool negative;
    float a;

    bits.f = v;
    if ((bits.u & 0x7F800000UL) == 0x7F800000UL && (bits.u & 0x007FFFFFUL) != 0UL) {
        w->lo = w->hi = 0UL;
        return;
    }
    negative = v < 0.0f;
    a = negative ? -v : v;
    if (a >= 9223372036854775808.0f) {
        w->lo = negative ? 0UL : 0xFFFFFFFFUL;
        w->hi = negative ? W64_SIGN : 0x7FFFFFFFUL;
        return;
    }
    if (a < 4294967296.0f) {
        w->hi = 0UL;
        w->lo = (uint32_t)a;
    } else {
        w->hi = (uint32_t)(a / 4294967296.0f);
        w->lo = (uint32_t)(a - (float)w->hi * 4294967296.0f);
    }
    if (negative) {
        w64_negate(w);
    }
}

/* One operation, in the function that the macros call: a call less on the
 * proxy's small stack than going through el_w64_op. */
#define W64_APPLY(w, op, x)                      \
    switch (op) {                                \
    case EL_W64_ADD: w64_add((w), (x)); break;   \
    case EL_W64_SUB: w64_sub((w), (x)); break;   \
    case EL_W64_MUL: w64_mul((w), (x)); break;   \
    default: w64_div((w), (x)); break;           \
    }

void el_w64_op(el_w64_t *w, uint8_t op, const el_w64_t *x)
{
    W64_APPLY(w, op, x)
}

/* One 32-bit operand, given as a magnitude and a sign for the
 * multiplication and division and as ``x`` for the sum and difference
 * (not W64_APPLY: a board that prunes functions keeps no 64-bit division).
 * A macro, not a function: a call level more overflows the F16 proxy's
 * 8051 stack (some 220 bytes) in a model as large as pneumatic_cylinder. */
#define W64_OP32(w, op, magnitude, negative, x) \
    do { \
        if ((op) == EL_W64_DIV) { \
            w64_div32((w), (magnitude), (negative)); \
        } else if ((op) == EL_W64_MUL) { \
            w64_mul32((w), (magnitude), (negative)); \
        } else if ((op) == EL_W64_ADD) { \
            w64_add((w), (x)); \
        } else { \
            w64_sub((w), (x)); \
        } \
    } while (0)

void el_w64_op_i32(el_w64_t *w, uint8_t op, int32_t v)
{
    el_w64_t x;
    el_w64_set_i32(&x, v);
    W64_OP32(w, op, v < 0 ? 0UL - (uint32_t)v : (uint32_t)v, v < 0, &x);
}

void el_w64_op_u32(el_w64_t *w, uint8_t op, uint32_t v)
{
    el_w64_t x;
    el_w64_set_u32(&x, v);
    W64_OP32(w, op, v, false, &x);
}

int8_t el_w64_cmp(const el_w64_t *a, const el_w64_t *b)
{
    /* Flipping the sign bits orders signed high words as unsigned ones. */
    uint32_t ah = a->hi ^ W64_SIGN, bh = b->hi ^ W64_SIGN;
    if (ah != bh) {
        return ah < bh ? (int8_t)-1 : (int8_t)1;
    }
    if (a->lo != b->lo) {
        return a->lo < b->lo ? (int8_t)-1 : (int8_t)1;
    }
    return 0;
}

int8_t el_w64_sign(const el_w64_t *w)
{
    if ((w->hi & W64_SIGN) != 0UL) {
        return -1;
    }
    return (w->hi != 0UL || w->lo != 0UL) ? (int8_t)1 : (int8_t)0;
}

int32_t el_w64_sat_i32(const el_w64_t *w, int32_t lo, int32_t hi)
{
    el_w64_t bound;
    el_w64_set_i32(&bound, lo);
    if (el_w64_cmp(w, &bound) < 0) {
        return lo;
    }
    el_w64_set_i32(&bound, hi);
    if (el_w64_cmp(w, &bound) > 0) {
        return hi;
    }
    /* Within int32_t: the low word is the value in two's complement. */
    return (w->lo & W64_SIGN) != 0UL ? -(int32_t)(~w->lo) - 1 : (int32_t)w->lo;
}

uint32_t el_w64_sat_u32(const el_w64_t *w, uint32_t lo, uint32_t hi)
{
    el_w64_t bound;
    el_w64_set_u32(&bound, lo);
    if (el_w64_cmp(w, &bound) < 0) {
        return lo;
    }
    el_w64_set_u32(&bound, hi);
    if (el_w64_cmp(w, &bound) > 0) {
        return hi;
    }
    return w->lo;
}

#if EL_WIDE_INT64
/* ---- el_wide.h's int64_t form: the same results with C's 64-bit type. A
 * product is checked on the operands' magnitudes in 32-bit halves (no
 * 64-bit division, which 8-bit parts pay for in flash and time). */

int64_t el_w_add(int64_t w, int64_t v)
{
    if (v > 0 && w > INT64_MAX - v) {
        return INT64_MAX;
    }
    if (v < 0 && w < INT64_MIN - v) {
        return INT64_MIN;
    }
    return w + v;
}

int64_t el_w_sub(int64_t w, int64_t v)
{
    if (v < 0 && w > INT64_MAX + v) {
        return INT64_MAX;
    }
    if (v > 0 && w < INT64_MIN + v) {
        return INT64_MIN;
    }
    return w - v;
}

/* a * b = (a >> 32) * b * 2^32 + (a & 0xFFFFFFFF) * b for magnitudes with
 * b < 2^32 (else both are at least 2^32: the product overflows) */
int64_t el_w_mul(int64_t w, int64_t v)
{
    bool negative = (w < 0) != (v < 0);
    uint64_t a = w < 0 ? 0u - (uint64_t)w : (uint64_t)w;
    uint64_t b = v < 0 ? 0u - (uint64_t)v : (uint64_t)v;
    uint64_t limit = (uint64_t)INT64_MAX + (negative ? 1u : 0u);
    uint64_t high;
    uint64_t low;
    if (b > 0xFFFFFFFFu) {
        high = a;
        a = b;
        b = high;
    }
    high = (a >> 32) * (b & 0xFFFFFFFFu);
    low = (a & 0xFFFFFFFFu) * (b & 0xFFFFFFFFu);
    if (b > 0xFFFFFFFFu || high > 0xFFFFFFFFu || (high << 32) > UINT64_MAX - low || (high << 32) + low > limit) {
        return negative ? INT64_MIN : INT64_MAX;
    }
    return w * v;
}

/* Toward zero; beyond the range its end (C leaves the conversion
 * undefined, and compilers give different ends); NaN: 0. As el_w64_set_f32. */
int64_t el_w_from_f32(float v)
{
    if (v >= 9223372036854775808.0f) {
        return INT64_MAX;
    }
    if (v <= -9223372036854775808.0f) {
        return INT64_MIN;
    }
    if (v < 0.0f || v >= 0.0f) {
        return (int64_t)v;
    }
    return 0; /* NaN, which no comparison holds for (`v != v` a compiler may fold) */
}

/* v != 0; INT64_MIN / -1 is INT64_MAX */
int64_t el_w_div(int64_t w, int64_t v)
{
    if (v == -1) {
        return w == INT64_MIN ? INT64_MAX : -w;
    }
    return w / v;
}
#endif
