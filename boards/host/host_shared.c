/* EasyLab host board: what the host board shares with the simulators of
 * other boards (the simulator harnesses' shared core sim_harness.c, the f16
 * board's proxy runner, which write traces and read stimuli with the host
 * board's own host_trace.c and host_stimulus.c): messages, the sizes and
 * names of the model's value types, durations on the command line. */
#include "host_internal.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

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

/* ---- durations ---- */

bool el_host_parse_duration(const char *text, uint64_t *us, const char **why)
{
    static const struct {
        const char *unit;
        uint64_t us;
    } units[] = {
        {"us", 1u}, {"ms", 1000u}, {"s", 1000000u}, {"m", 60000000u},
        {"min", 60000000u}, {"h", 3600000000u},
    };
    const char *p = text;
    uint64_t whole = 0, frac = 0, frac_scale = 1, unit_us = 0;
    size_t frac_digits = 0, i;

    *why = "not a duration (give a number and a unit: 10s, 1.5s, 500ms, 250us, 2m, 1h)";
    if (*p < '0' || *p > '9')
        return false;
    for (; *p >= '0' && *p <= '9'; p++) {
        if (whole > (UINT64_MAX - 9u) / 10u) {
            *why = "duration too long";
            return false;
        }
        whole = whole * 10u + (uint64_t)(*p - '0');
    }
    if (*p == '.') {
        const char *digits = ++p, *end;
        if (*p < '0' || *p > '9')
            return false;
        while (*p >= '0' && *p <= '9')
            p++;
        end = p;
        while (end > digits && end[-1] == '0') /* 1.50s is 1.5s */
            end--;
        frac_digits = (size_t)(end - digits);
        if (frac_digits > 9u) {
            *why = "duration finer than 1 us";
            return false;
        }
        for (i = 0; i < frac_digits; i++) {
            frac = frac * 10u + (uint64_t)(digits[i] - '0');
            frac_scale *= 10u;
        }
    }
    if (*p == ' ')
        p++;
    if (*p == '\0') {
        *why = "a duration needs a unit: us, ms, s, m or h (e.g. 10s, 500ms)";
        return false;
    }
    for (i = 0; i < sizeof units / sizeof units[0]; i++)
        if (strcmp(p, units[i].unit) == 0)
            unit_us = units[i].us;
    if (unit_us == 0) {
        *why = "unknown time unit (give us, ms, s, m or h: 10s, 1.5s, 500ms, 250us, 2m)";
        return false;
    }
    /* frac < 10^9 and unit_us <= 3.6e9: the product fits in 64 bits. */
    if ((frac * unit_us) % frac_scale != 0u) {
        *why = "duration finer than 1 us";
        return false;
    }
    if (whole > (UINT64_MAX - (frac * unit_us) / frac_scale) / unit_us) {
        *why = "duration too long";
        return false;
    }
    *us = whole * unit_us + (frac * unit_us) / frac_scale;
    return true;
}
