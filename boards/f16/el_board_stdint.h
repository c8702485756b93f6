/* EasyLab f16 board: the fixed-width types of runtime_c/el_types.h for a C89
 * compiler without <stdint.h> (Softune fcc907s; the proxy checks compile the
 * same files with gcc -std=c89, clang for MSP430 and sdcc). Chosen by the
 * ranges of <limits.h>, so one header serves a 16-bit int (F2MC-16, MSP430,
 * 8051) and the host's 32-bit int alike. There is no 64-bit type: C89 has
 * none, and el_types.h then computes wide values in software (el_wide.h). */
#ifndef EL_BOARD_STDINT_H
#define EL_BOARD_STDINT_H

#include <limits.h>

typedef signed char int8_t;
typedef unsigned char uint8_t;

#if INT_MAX == 32767
typedef int int16_t;
typedef unsigned int uint16_t;
#define UINT16_MAX 65535u
#elif SHRT_MAX == 32767
typedef short int16_t;
typedef unsigned short uint16_t;
#define UINT16_MAX 65535
#else
#error "no 16-bit integer type"
#endif

#if INT_MAX == 2147483647
typedef int int32_t;
typedef unsigned int uint32_t;
#define INT32_MIN (-2147483647 - 1)
#define INT32_MAX 2147483647
#define UINT32_MAX 4294967295u
#elif LONG_MAX == 2147483647
typedef long int32_t;
typedef unsigned long uint32_t;
#define INT32_MIN (-2147483647L - 1L)
#define INT32_MAX 2147483647L
#define UINT32_MAX 4294967295UL
#else
#error "no 32-bit integer type"
#endif

/* The limits with the types C99's <stdint.h> gives them (after promotion). */
#define INT8_MIN (-127 - 1)
#define INT8_MAX 127
#define UINT8_MAX 255
#define INT16_MIN (-32767 - 1)
#define INT16_MAX 32767

#endif /* EL_BOARD_STDINT_H */
