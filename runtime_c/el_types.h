/* EasyLab runtime: basic types and the arithmetic of the IR (docs/ir.md).
 *
 * Every generated file and every runtime file includes this header first.
 * Portable C99 (also C89 with a 16-bit int for the F16 port): fixed-width
 * types, no heap, no recursion.
 */
#ifndef EL_TYPES_H
#define EL_TYPES_H

#include <stdint.h>
#include <stddef.h>
#include <float.h>

#if defined(__STDC_VERSION__) && __STDC_VERSION__ >= 199901L
#include <stdbool.h>
#elif !defined(__bool_true_false_are_defined)
typedef unsigned char bool;
#define true 1
#define false 0
#endif

#define EL_RUNTIME_VERSION 1

/* Run-time `time`: milliseconds in a uint32, saturating (docs/language.md). */
typedef uint32_t el_time_t;
#define EL_TIME_MAX UINT32_MAX

/* Saturate v into [lo, hi]. Arguments are evaluated more than once. */
#define EL_CLAMP(v, lo, hi) ((v) < (lo) ? (lo) : ((v) > (hi) ? (hi) : (v)))

/* Inline helpers: `static inline` where the compiler has it (C99). */
#if defined(__STDC_VERSION__) && __STDC_VERSION__ >= 199901L
#define EL_INLINE static inline
#else
#define EL_INLINE static
#endif

/* Saturation as functions, so that generic actor code never compares a
 * narrow type with a bound it cannot reach (which compilers warn about). */
EL_INLINE int64_t el_clamp_i64(int64_t v, int64_t lo, int64_t hi)
{
    return v < lo ? lo : (v > hi ? hi : v);
}

EL_INLINE float el_clamp_f32(float v, float lo, float hi)
{
    return v < lo ? lo : (v > hi ? hi : v);
}

/* Three-way comparison of model integers (-1, 0, 1): generated guards
 * compare through these, so that a comparison whose outcome the types
 * already decide (an unsigned value >= 0) is no compiler warning. */
#define EL_CMP_FN(name, T) \
    EL_INLINE int8_t el_cmp_##name(T a, T b) { return (int8_t)(a < b ? -1 : (a > b ? 1 : 0)); }
EL_CMP_FN(i8, int8_t)
EL_CMP_FN(u8, uint8_t)
EL_CMP_FN(i16, int16_t)
EL_CMP_FN(u16, uint16_t)
EL_CMP_FN(i32, int32_t)
EL_CMP_FN(u32, uint32_t)
#undef EL_CMP_FN

/* Compare with an operator given as a compile-time string ("<", "<=", ...):
 * the compiler folds the string tests away. */
#define EL_COMPARE(op, a, b) \
    ((op)[0] == '<' ? ((op)[1] == '=' ? (a) <= (b) : (a) < (b)) : \
     (op)[0] == '>' ? ((op)[1] == '=' ? (a) >= (b) : (a) > (b)) : \
     (op)[0] == '=' ? (a) == (b) : (a) != (b))

/* Read-only tables: in flash where the board can read it from there. */
#ifndef EL_ROM
#define EL_ROM
#endif
#ifndef EL_ROM_READ_U16
#define EL_ROM_READ_U16(p) (*(const uint16_t *)(p))
#endif
#ifndef EL_ROM_READ_U32
#define EL_ROM_READ_U32(p) (*(const uint32_t *)(p))
#endif
#ifndef EL_ROM_READ_U8
#define EL_ROM_READ_U8(p) (*(const uint8_t *)(p))
#endif

/* Wrapping integer arithmetic of model expressions: computed in the
 * unsigned type of the same width, so overflow is defined and the result
 * is the same on every board (two's complement). */
#define EL_WRAP_ADD(T, U, a, b) ((T)(U)((U)(a) + (U)(b)))
#define EL_WRAP_SUB(T, U, a, b) ((T)(U)((U)(a) - (U)(b)))
#define EL_WRAP_MUL(T, U, a, b) ((T)(U)((U)(a) * (U)(b)))
#define EL_WRAP_NEG(T, U, a) ((T)(U)(0u - (U)(a)))

int8_t el_div_i8(int8_t a, int8_t b);
int16_t el_div_i16(int16_t a, int16_t b);
int32_t el_div_i32(int32_t a, int32_t b);
uint8_t el_div_u8(uint8_t a, uint8_t b);
uint16_t el_div_u16(uint16_t a, uint16_t b);
uint32_t el_div_u32(uint32_t a, uint32_t b);
int8_t el_mod_i8(int8_t a, int8_t b);
int16_t el_mod_i16(int16_t a, int16_t b);
int32_t el_mod_i32(int32_t a, int32_t b);
uint8_t el_mod_u8(uint8_t a, uint8_t b);
uint16_t el_mod_u16(uint16_t a, uint16_t b);
uint32_t el_mod_u32(uint32_t a, uint32_t b);
float el_div_f32(float a, float b);

/* time + time and time - time saturate at 0 and EL_TIME_MAX. */
el_time_t el_time_add(el_time_t a, el_time_t b);
el_time_t el_time_sub(el_time_t a, el_time_t b);

#endif /* EL_TYPES_H */
