/* EasyLab PIC18 board: 64-bit integers for a compiler without them.
 *
 * sdcc's pic16 port has no `long long`. The board's build lowers every
 * 64-bit integer of the portable C files (runtime, generated code, the
 * port) to an el_w64_t and each operation on it to a call below
 * (boards/pic18/lower64.py; docs/boards.md, "64-bit integers"). The
 * functions have C's semantics for int64_t and uint64_t as gcc implements
 * them: two's complement, wrapping, division truncating toward zero, `>>`
 * of a negative value arithmetic. Results go through `r`, which may be an
 * operand. Division by zero, which C leaves undefined, gives 0.
 *
 * Microchip's XC8 (C99 mode) has 64-bit `long long` on the PIC18: with it
 * the lowering is not needed (docs/boards.md, "MPLAB XC8").
 */
#ifndef EL_PIC18_W64_H
#define EL_PIC18_W64_H

#include <stddef.h>
#include <stdint.h>

/* A 64-bit integer as a little-endian uint64 lies in memory: the runtime's
 * el_w64_t (runtime_c/el_wide.h, the same declaration under the same guard:
 * this header is read first, before the runtime's are on the include path).
 * The lowering names it by its tag where it may come before this header. */
#ifndef EL_W64_DECLARED
#define EL_W64_DECLARED
typedef struct el_w64 {
    uint32_t lo; /* bits 0..31 */
    uint32_t hi; /* bits 32..63; bit 63 is the sign */
} el_w64_t;
#endif

void el_w64_from_i32(el_w64_t *r, int32_t v);
void el_w64_from_u32(el_w64_t *r, uint32_t v);
void el_w64_from_f32s(el_w64_t *r, float v); /* toward zero, as (int64_t)v */
void el_w64_from_f32u(el_w64_t *r, float v); /* toward zero, as (uint64_t)v */
float el_w64_to_f32s(const el_w64_t *a);     /* nearest, ties to even, as (float)(int64_t)a */
float el_w64_to_f32u(const el_w64_t *a);     /* nearest, ties to even, as (float)(uint64_t)a */

void el_w64_add(el_w64_t *r, const el_w64_t *a, const el_w64_t *b);
void el_w64_sub(el_w64_t *r, const el_w64_t *a, const el_w64_t *b);
void el_w64_mul(el_w64_t *r, const el_w64_t *a, const el_w64_t *b);
void el_w64_divs(el_w64_t *r, const el_w64_t *a, const el_w64_t *b);
void el_w64_mods(el_w64_t *r, const el_w64_t *a, const el_w64_t *b);
void el_w64_divu(el_w64_t *r, const el_w64_t *a, const el_w64_t *b);
void el_w64_modu(el_w64_t *r, const el_w64_t *a, const el_w64_t *b);
void el_w64_and(el_w64_t *r, const el_w64_t *a, const el_w64_t *b);
void el_w64_or(el_w64_t *r, const el_w64_t *a, const el_w64_t *b);
void el_w64_xor(el_w64_t *r, const el_w64_t *a, const el_w64_t *b);
void el_w64_neg(el_w64_t *r, const el_w64_t *a);
void el_w64_not(el_w64_t *r, const el_w64_t *a);
void el_w64_shl(el_w64_t *r, const el_w64_t *a, uint8_t n);
void el_w64_shrs(el_w64_t *r, const el_w64_t *a, uint8_t n); /* arithmetic */
void el_w64_shru(el_w64_t *r, const el_w64_t *a, uint8_t n); /* logical */
int8_t el_w64_cmps(const el_w64_t *a, const el_w64_t *b);  /* -1, 0, 1 */
int8_t el_w64_cmpu(const el_w64_t *a, const el_w64_t *b);

/* A struct assignment becomes a call of memcpy (lower64.py): sdcc 4.2's own
 * copy calls a __memcpy it does not declare. */
void *memcpy(void *dst, const void *src, size_t n);

#if defined(EL_W64_LOWERING)
/* Only while lowering (never compiled): the types the program is written
 * with, so that the lowering sees its 64-bit integers. */
typedef long long int64_t;
typedef unsigned long long uint64_t;
#define INT64_MAX 9223372036854775807LL
#define INT64_MIN (-9223372036854775807LL - 1LL)
#define UINT64_MAX 18446744073709551615ULL
#define INT64_C(c) c##LL
#define UINT64_C(c) c##ULL
#endif

#endif /* EL_PIC18_W64_H */
