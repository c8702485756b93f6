/* EasyLab runtime: included once, where a generated file (model.c, an actor
 * plug-in) begins its actor code, which it gives last (docs/language.md,
 * "Actor code and compiler warnings").
 *
 * A compile-time argument or a type parameter may decide one of an actor's
 * comparisons (`x < off_below` with 0 for a uint8, `a < 0` for an unsigned
 * T), which compilers warn about and boards' -Werror makes an error; an
 * argument equal to another operand makes both sides of a comparison the
 * same text (`(x & k) <= (x & -1)` with k = -1: "self-comparison always
 * evaluates to true"). Exactly those warnings are off from here to the end
 * of the file: gcc's -Wtype-limits and -Wtautological-compare, clang's
 * tautological comparisons, gcc's and
 * clang's -Wsign-compare (which judge `~(uint32_t)x <= k` by whether k is a
 * constant: "comparison of promoted bitwise complement of an unsigned value
 * with constant"), sdcc's 94
 * ("comparison is always true/false due to limited range of data type"),
 * which sdcc 4.2 cannot switch on again (#pragma save/restore leave
 * warnings alone): hence last. Every other warning stays an error.
 */
#ifndef EL_ACTOR_CODE_H
#define EL_ACTOR_CODE_H

#if defined(__clang__)
#pragma clang diagnostic ignored "-Wtautological-compare"
#pragma clang diagnostic ignored "-Wtautological-constant-compare"
#pragma clang diagnostic ignored "-Wtautological-constant-out-of-range-compare"
#pragma clang diagnostic ignored "-Wtype-limits"
#pragma clang diagnostic ignored "-Wsign-compare"
#elif defined(__GNUC__)
#pragma GCC diagnostic ignored "-Wtype-limits"
#if __GNUC__ >= 6 /* the warning is gcc 6's (avr-gcc 5 has none) */
#pragma GCC diagnostic ignored "-Wtautological-compare"
#endif
#pragma GCC diagnostic ignored "-Wsign-compare"
#elif defined(__SDCC)
#pragma disable_warning 94
#endif

#endif /* EL_ACTOR_CODE_H */
