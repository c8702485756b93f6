/* EasyLab f16 board, 16-bit proxy: <float.h> for sdcc --std-c89.
 *
 * sdcc 4.2's own float.h declares its float helpers as returning _Bool,
 * which --std-c89 does not know, and sdcc has them built in anyway: the
 * proxy build puts this folder first on the include path. The values are
 * C89's for IEEE 754 single precision, sdcc's float. */
#ifndef EL_F16P_FLOAT_H
#define EL_F16P_FLOAT_H

#define FLT_RADIX 2
#define FLT_ROUNDS 1
#define FLT_MANT_DIG 24
#define FLT_DIG 6
#define FLT_MIN_EXP (-125)
#define FLT_MIN_10_EXP (-37)
#define FLT_MAX_EXP 128
#define FLT_MAX_10_EXP 38
#define FLT_MIN 1.17549435E-38F
#define FLT_MAX 3.40282347E+38F
#define FLT_EPSILON 1.19209290E-07F

#endif /* EL_F16P_FLOAT_H */
