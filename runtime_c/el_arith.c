/* EasyLab runtime: the arithmetic of model expressions that C leaves
 * undefined or implementation-defined (docs/ir.md, "expressions"):
 * division by zero gives 0 (x % 0 gives x), the most negative value
 * divided by -1 wraps, time saturates. A C89 build also gets el_types.h's
 * helpers (el_cmp_*, el_clamp_*) defined here, once. */
#define EL_DEFINE_HELPERS 1
#include "el_types.h"

#define EL_DIV_SIGNED(name, T, MIN)                        \
    T el_div_##name(T a, T b)                              \
    {                                                      \
        if (b == 0) { return 0; }                          \
        if (b == -1) { return (a == (MIN)) ? a : (T)-a; }  \
        return (T)(a / b);                                 \
    }                                                      \
    T el_mod_##name(T a, T b)                              \
    {                                                      \
        if (b == 0) { return a; }                          \
        if (b == -1) { return 0; }                         \
        return (T)(a % b);                                 \
    }

#define EL_DIV_UNSIGNED(name, T)                           \
    T el_div_##name(T a, T b) { return b == 0u ? 0u : (T)(a / b); } \
    T el_mod_##name(T a, T b) { return b == 0u ? a : (T)(a % b); }

EL_DIV_SIGNED(i8, int8_t, INT8_MIN)
EL_DIV_SIGNED(i16, int16_t, INT16_MIN)
EL_DIV_SIGNED(i32, int32_t, INT32_MIN)
EL_DIV_UNSIGNED(u8, uint8_t)
EL_DIV_UNSIGNED(u16, uint16_t)
EL_DIV_UNSIGNED(u32, uint32_t)

float el_div_f32(float a, float b)
{
    return b == 0.0f ? 0.0f : a / b;
}

el_time_t el_time_add(el_time_t a, el_time_t b)
{
    return (a > EL_TIME_MAX - b) ? EL_TIME_MAX : (el_time_t)(a + b);
}

el_time_t el_time_sub(el_time_t a, el_time_t b)
{
    return (a < b) ? 0u : (el_time_t)(a - b);
}
