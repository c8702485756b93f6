/* EasyLab runtime: basic types and the arithmetic of the IR (docs/ir.md).
 *
 * Every generated file and every runtime file includes this header first.
 * Portable C99, and C89 with a 16-bit int (the f16 board): fixed-width
 * types, no heap, no recursion.
 */
#ifndef EL_TYPES_H
#define EL_TYPES_H

/* A board whose compiler has no <stdint.h> (C89) defines EL_BOARD_STDINT
 * and gives the fixed-width types and their limits in el_board_stdint.h. */
#if defined(EL_BOARD_STDINT)
#include "el_board_stdint.h"
#else
#include <stdint.h>
#endif
#include <stddef.h>
#include <float.h>

/* Whether the compiler has a 64-bit integer type: C99 compilers do; C89
 * ones (Softune fcc907s, sdcc --std-c89) do not, and the runtime then does
 * its wide arithmetic in software (el_wide.h) and counts absolute ticks in
 * 32 bits. */
#if defined(INT64_MAX)
#define EL_HAS_INT64 1
#else
#define EL_HAS_INT64 0
#endif

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

/* The absolute logical tick (the dispatcher's count of instants' ticks).
 * 64-bit: traces run long. Without a 64-bit type, or on a board that asks
 * for it (EL_TICK_32: 8-bit parts, where 64-bit additions cost flash and
 * time at every instant), it wraps after 2^32 ticks (49.7 days of 1 ms
 * ticks), which nothing in a firmware notices: the port's waits and the
 * lateness count compare 32-bit ticks wrap-safely (instants are less than
 * a hyperperiod apart, which fits 32 bits), and a simulator's harness
 * extends the ticks it reads to 64 bits (sim_tick_extend).
 *
 * EL_TICK_16: a board that narrows ticks passes it for a program whose
 * timing allows 16 bits (the IR's `tick_bits`, docs/ir.md, "Dispatcher
 * widths"): hyperperiod and deadlines under 2^15 ticks, 2^15 ticks at
 * least 10 s. Then the tick wraps after 2^16 ticks. A remote-execution
 * proxy and a node of a Modbus round keep 32 bits: their links compare
 * ticks in 32 (el_remote.c, the round's gate).
 *
 * el_wtick_t: the tick modulo 2^16 or 2^32, what the ports wait for and
 * count in real time and the dispatch table's ticks within the
 * hyperperiod; EL_TICK_REACHED compares two of them wrap-safely. */
#if defined(EL_TICK_16) && EL_TICK_16 && !(defined(EL_REMOTE_PROXY) && EL_REMOTE_PROXY) && \
    !defined(EL_ROUND_MASTER) && !defined(EL_ROUND_SLAVE)
#define EL_TICK_BITS 16
typedef uint16_t el_tick_t;
typedef uint16_t el_wtick_t;
#define EL_WTICK_HALF 0x8000u
#define EL_ROM_READ_WTICK(p) EL_ROM_READ_U16(p)
#else
#if EL_HAS_INT64 && !(defined(EL_TICK_32) && EL_TICK_32)
typedef uint64_t el_tick_t;
#else
typedef uint32_t el_tick_t;
#endif
typedef uint32_t el_wtick_t;
#define EL_WTICK_HALF 0x80000000UL
#define EL_ROM_READ_WTICK(p) EL_ROM_READ_U32(p)
#endif
/* Whether tick `t` has come at real tick `now` (el_wtick_t both): true from
 * `t` on, for less than half the counter's range. */
#define EL_TICK_REACHED(now, t) ((el_wtick_t)((el_wtick_t)(now) - (el_wtick_t)(t)) < (el_wtick_t)EL_WTICK_HALF)

/* Saturate v into [lo, hi]. Arguments are evaluated more than once. */
#define EL_CLAMP(v, lo, hi) ((v) < (lo) ? (lo) : ((v) > (hi) ? (hi) : (v)))

/* Inline helpers: `static inline` where the compiler has it (C99). A C89
 * compiler has no inline, and warns about a static function a file does
 * not use: there EL_HELPER only declares the helper, and el_arith.c (which
 * defines EL_DEFINE_HELPERS) defines it once. */
#if defined(__STDC_VERSION__) && __STDC_VERSION__ >= 199901L
#define EL_INLINE static inline
#define EL_HELPER(decl, body) static inline decl body
#else
#define EL_INLINE static
#if defined(EL_DEFINE_HELPERS)
#define EL_HELPER(decl, body) decl; decl body
#else
#define EL_HELPER(decl, body) decl;
#endif
#endif

/* Saturation as functions, so that generic actor code never compares a
 * narrow type with a bound it cannot reach (which compilers warn about). */
#if EL_HAS_INT64
EL_HELPER(int64_t el_clamp_i64(int64_t v, int64_t lo, int64_t hi),
          { return v < lo ? lo : (v > hi ? hi : v); })
#endif
EL_HELPER(int32_t el_clamp_i32(int32_t v, int32_t lo, int32_t hi),
          { return v < lo ? lo : (v > hi ? hi : v); })
EL_HELPER(uint32_t el_clamp_u32(uint32_t v, uint32_t lo, uint32_t hi),
          { return v < lo ? lo : (v > hi ? hi : v); })
EL_HELPER(float el_clamp_f32(float v, float lo, float hi),
          { return v < lo ? lo : (v > hi ? hi : v); })

/* Three-way comparison of model integers (-1, 0, 1): generated guards
 * compare through these, so that a comparison whose outcome the types
 * already decide (an unsigned value >= 0) is no compiler warning. */
#define EL_CMP_FN(name, T) \
    EL_HELPER(int8_t el_cmp_##name(T a, T b), { return (int8_t)(a < b ? -1 : (a > b ? 1 : 0)); })
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

/* A function kept out of its callers: a hot loop then has the registers to
 * itself (avr-gcc otherwise inlines a static function called once and
 * spills the loop's variables to the stack). */
#ifndef EL_NOINLINE
#if defined(__GNUC__)
#define EL_NOINLINE __attribute__((noinline))
#else
#define EL_NOINLINE
#endif
#endif

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
#ifndef EL_ROM_READ_PTR
#define EL_ROM_READ_PTR(p) (*(const void *const *)(p))
#endif

/* Wrapping integer arithmetic of model expressions: computed in the
 * unsigned type of the same width, so overflow is defined and the result
 * is the same on every board (two's complement). The product goes through
 * `* 1u`: with a 32-bit int, two uint16_t operands are promoted to (signed)
 * int, and 65535 * 65535 would overflow it; an unsigned operand makes the
 * multiplication unsigned on every int width. */
#define EL_WRAP_ADD(T, U, a, b) ((T)(U)((U)(a) + (U)(b)))
#define EL_WRAP_SUB(T, U, a, b) ((T)(U)((U)(a) - (U)(b)))
#define EL_WRAP_MUL(T, U, a, b) ((T)(U)((U)(a) * 1u * (U)(b)))
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

/* Wide integer arithmetic for actor code (64-bit, in software without a
 * 64-bit type). */
#include "el_wide.h"

#endif /* EL_TYPES_H */
