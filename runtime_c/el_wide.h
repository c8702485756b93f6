/* EasyLab runtime: wide integer arithmetic for actor code (docs/language.md,
 * "Inline C convention").
 *
 * The standard library's integer actors compute in a type wider than any
 * model type and saturate the result into their own (Add, Gain, PID, ...):
 * `el_wide_t`, a signed 64-bit integer. On a compiler with a 64-bit type it
 * is int64_t and every operation below is the C operator. A C89 compiler
 * (the f16 board: Softune fcc907s, and sdcc --std-c89 for its proxy) has
 * none: then el_wide_t is a pair of 32-bit words and the operations are
 * the functions of el_wide.c, which give the same results: sums,
 * differences, products and quotients saturate at the 64-bit range (so that
 * an actor saturating a result into its own type gets the right end of it:
 * UINT32_MAX * UINT32_MAX is beyond int64_t, and wrapping made it 0),
 * division truncates toward zero.
 *
 * The operations are statements on an lvalue `w` of type el_wide_t, one
 * operand each (an accumulator), because the software form can neither
 * return nor pass a structure by value on every compiler (sdcc cannot):
 *
 *     el_wide_t w;
 *     EL_W_SET_I(w, a);        w = a        (a: any integer type but uint32)
 *     EL_W_ADD_I(w, b);        w += b
 *     EL_W_MUL_I(w, k);        w *= k
 *     EL_W_DIV_I(w, 1000);     w /= 1000    (truncating; the divisor must not be 0)
 *     y = (int16_t)EL_W_SAT_I32(w, -32768, 32767);
 *
 * _I takes a value that fits int32_t, _U one that fits uint32_t, _W another
 * el_wide_t, _F a float (SET only: truncated toward zero, saturated at the
 * wide range, 0 for NaN). EL_W_SAT_I32/U32 clamp into [lo, hi] and give the
 * int32_t/uint32_t; EL_W_NARROW_I32/U32 give a value that fits them;
 * EL_W_CMP compares two wide values, EL_W_SIGN one with zero (-1, 0, 1).
 */
#ifndef EL_WIDE_H
#define EL_WIDE_H

#include "el_types.h"

/* The software form: two's complement in two 32-bit words. Its functions
 * (el_wide.c) are compiled on every board, so that the host's tests can
 * check them against native 64-bit arithmetic. */
#ifndef EL_W64_DECLARED /* boards/pic18/el_pic18_w64.h declares the same */
#define EL_W64_DECLARED
typedef struct el_w64 {
    uint32_t lo; /* bits 0..31 */
    uint32_t hi; /* bits 32..63; bit 63 is the sign */
} el_w64_t;
#endif

enum { EL_W64_ADD = 0, EL_W64_SUB = 1, EL_W64_MUL = 2, EL_W64_DIV = 3 };

void el_w64_set_i32(el_w64_t *w, int32_t v);
void el_w64_set_u32(el_w64_t *w, uint32_t v);
void el_w64_set_f32(el_w64_t *w, float v);
/* *w = *w op *x, saturating at the 64-bit range; DIV truncates toward zero,
 * x / 0 is 0. */
void el_w64_op(el_w64_t *w, uint8_t op, const el_w64_t *x);
void el_w64_op_i32(el_w64_t *w, uint8_t op, int32_t v);
void el_w64_op_u32(el_w64_t *w, uint8_t op, uint32_t v);
int32_t el_w64_sat_i32(const el_w64_t *w, int32_t lo, int32_t hi);
uint32_t el_w64_sat_u32(const el_w64_t *w, uint32_t lo, uint32_t hi);
int8_t el_w64_cmp(const el_w64_t *a, const el_w64_t *b);
int8_t el_w64_sign(const el_w64_t *w);

/* EL_WIDE_SOFTWARE: a board whose compiler has int64_t only through a
 * lowering of its own (the PIC18's) takes the software form, which the
 * F16's 8051 proxy runs through the same compiler family. */
#if EL_HAS_INT64 && !(defined(EL_WIDE_SOFTWARE) && EL_WIDE_SOFTWARE)
#define EL_WIDE_INT64 1
#else
#define EL_WIDE_INT64 0
#endif

#if EL_WIDE_INT64

typedef int64_t el_wide_t;

/* The saturating operations on int64_t (el_wide.c; functions, not inline:
 * the PIC18's lowered 64-bit arithmetic is one copy then). None
 * overflows; el_w_div needs v != 0. el_w_from_f32 truncates toward zero,
 * saturates beyond the range (where C leaves the conversion undefined and
 * compilers give different ends) and gives 0 for NaN, as the software
 * form does. */
int64_t el_w_add(int64_t w, int64_t v);
int64_t el_w_sub(int64_t w, int64_t v);
int64_t el_w_mul(int64_t w, int64_t v);
int64_t el_w_div(int64_t w, int64_t v);
int64_t el_w_from_f32(float v);

#define EL_W_SET_I(w, v) ((w) = (int64_t)(v))
#define EL_W_SET_U(w, v) ((w) = (int64_t)(v))
#define EL_W_SET_F(w, v) ((w) = el_w_from_f32((float)(v)))
#define EL_W_SET_W(w, x) ((w) = (x))
#define EL_W_ADD_I(w, v) ((w) = el_w_add((w), (int64_t)(v)))
#define EL_W_ADD_U(w, v) ((w) = el_w_add((w), (int64_t)(v)))
#define EL_W_ADD_W(w, x) ((w) = el_w_add((w), (x)))
#define EL_W_SUB_I(w, v) ((w) = el_w_sub((w), (int64_t)(v)))
#define EL_W_SUB_U(w, v) ((w) = el_w_sub((w), (int64_t)(v)))
#define EL_W_SUB_W(w, x) ((w) = el_w_sub((w), (x)))
#define EL_W_MUL_I(w, v) ((w) = el_w_mul((w), (int64_t)(v)))
#define EL_W_MUL_U(w, v) ((w) = el_w_mul((w), (int64_t)(v)))
#define EL_W_MUL_W(w, x) ((w) = el_w_mul((w), (x)))
#define EL_W_DIV_I(w, v) ((w) = el_w_div((w), (int64_t)(v)))
#define EL_W_DIV_U(w, v) ((w) = el_w_div((w), (int64_t)(v)))
#define EL_W_DIV_W(w, x) ((w) = el_w_div((w), (x)))
#define EL_W_SAT_I32(w, lo, hi) ((int32_t)el_clamp_i64((int64_t)(w), (int64_t)(lo), (int64_t)(hi)))
#define EL_W_SAT_U32(w, lo, hi) ((uint32_t)el_clamp_i64((int64_t)(w), (int64_t)(lo), (int64_t)(hi)))
#define EL_W_NARROW_I32(w) ((int32_t)(w))
#define EL_W_NARROW_U32(w) ((uint32_t)(w))
#define EL_W_CMP(a, b) ((a) < (b) ? -1 : ((a) > (b) ? 1 : 0))
#define EL_W_SIGN(w) ((w) < 0 ? -1 : ((w) > 0 ? 1 : 0))

#else

typedef el_w64_t el_wide_t;

#define EL_W_SET_I(w, v) el_w64_set_i32(&(w), (int32_t)(v))
#define EL_W_SET_U(w, v) el_w64_set_u32(&(w), (uint32_t)(v))
#define EL_W_SET_F(w, v) el_w64_set_f32(&(w), (float)(v))
#define EL_W_SET_W(w, x) ((w) = (x))
#define EL_W_ADD_I(w, v) el_w64_op_i32(&(w), EL_W64_ADD, (int32_t)(v))
#define EL_W_ADD_U(w, v) el_w64_op_u32(&(w), EL_W64_ADD, (uint32_t)(v))
#define EL_W_ADD_W(w, x) el_w64_op(&(w), EL_W64_ADD, &(x))
#define EL_W_SUB_I(w, v) el_w64_op_i32(&(w), EL_W64_SUB, (int32_t)(v))
#define EL_W_SUB_U(w, v) el_w64_op_u32(&(w), EL_W64_SUB, (uint32_t)(v))
#define EL_W_SUB_W(w, x) el_w64_op(&(w), EL_W64_SUB, &(x))
#define EL_W_MUL_I(w, v) el_w64_op_i32(&(w), EL_W64_MUL, (int32_t)(v))
#define EL_W_MUL_U(w, v) el_w64_op_u32(&(w), EL_W64_MUL, (uint32_t)(v))
#define EL_W_MUL_W(w, x) el_w64_op(&(w), EL_W64_MUL, &(x))
#define EL_W_DIV_I(w, v) el_w64_op_i32(&(w), EL_W64_DIV, (int32_t)(v))
#define EL_W_DIV_U(w, v) el_w64_op_u32(&(w), EL_W64_DIV, (uint32_t)(v))
#define EL_W_DIV_W(w, x) el_w64_op(&(w), EL_W64_DIV, &(x))
#define EL_W_SAT_I32(w, lo, hi) el_w64_sat_i32(&(w), (int32_t)(lo), (int32_t)(hi))
#define EL_W_SAT_U32(w, lo, hi) el_w64_sat_u32(&(w), (uint32_t)(lo), (uint32_t)(hi))
#define EL_W_NARROW_I32(w) el_w64_sat_i32(&(w), INT32_MIN, INT32_MAX)
#define EL_W_NARROW_U32(w) el_w64_sat_u32(&(w), 0UL, UINT32_MAX)
#define EL_W_CMP(a, b) el_w64_cmp(&(a), &(b))
#define EL_W_SIGN(w) el_w64_sign(&(w))

#endif

#endif /* EL_WIDE_H */
