/* EasyLab host board: what the host board shares with the AVR board's
 * simulator harness (which writes traces and reads stimuli with the host
 * board's own host_trace.c and host_stimulus.c): messages, and the sizes
 * and names of the model's value types. */
#include "host_internal.h"

#include <stdarg.h>
#include <stdio.h>

void el_host_error(const char *fmt, ...)
{
    va_list ap;
    fprintf(stderr, "%s: ", el_host_prog);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
}


size_t el_host_type_size(uint8_t type)
{
    switch (type) {
    case EL_T_BOOL: return sizeof(bool);
    case EL_T_I8: return sizeof(int8_t);
    case EL_T_U8: return sizeof(uint8_t);
    case EL_T_I16: return sizeof(int16_t);
    case EL_T_U16: return sizeof(uint16_t);
    case EL_T_I32: return sizeof(int32_t);
    case EL_T_U32: return sizeof(uint32_t);
    case EL_T_F32: return sizeof(float);
    case EL_T_TIME: return sizeof(el_time_t);
    default: return 0;
    }
}

const char *el_host_type_name(uint8_t type)
{
    static const char *const names[] = {"bool", "int8", "uint8", "int16", "uint16",
                                        "int32", "uint32", "float32", "time"};
    return type < sizeof names / sizeof names[0] ? names[type] : "?";
}
