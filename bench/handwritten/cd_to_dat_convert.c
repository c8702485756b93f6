/* Hand-written reference for the benchmark: cd_to_dat's Convert dataflow as
 * a C programmer would write it, stage after stage over whole arrays (the
 * flat single-appearance schedule: 147 src, 147 b, 98 c, 28 d, 32 e, 160 f,
 * 1 checksum). */
#include <stdint.h>

static uint32_t n;
static uint32_t acc_b, acc_c, acc_d, acc_e, acc_f, sum;
static uint32_t ab[147], bc[294], cd[196], de[224], ef[160], fg[160];

uint32_t hw_checksum;

void hw_convert(void)
{
    uint16_t i, k;
    for (i = 0; i < 147u; i++) ab[i] = ++n;
    for (i = 0; i < 147u; i++) {                   /* b: 1 in, 2 out */
        acc_b += ab[i];
        for (k = 0; k < 2u; k++) bc[2u * i + k] = acc_b + k;
    }
    for (i = 0; i < 98u; i++) {                    /* c: 3 in, 2 out */
        for (k = 0; k < 3u; k++) acc_c += bc[3u * i + k];
        for (k = 0; k < 2u; k++) cd[2u * i + k] = acc_c + k;
    }
    for (i = 0; i < 28u; i++) {                    /* d: 7 in, 8 out */
        for (k = 0; k < 7u; k++) acc_d += cd[7u * i + k];
        for (k = 0; k < 8u; k++) de[8u * i + k] = acc_d + k;
    }
    for (i = 0; i < 32u; i++) {                    /* e: 7 in, 5 out */
        for (k = 0; k < 7u; k++) acc_e += de[7u * i + k];
        for (k = 0; k < 5u; k++) ef[5u * i + k] = acc_e + k;
    }
    for (i = 0; i < 160u; i++) {                   /* f: 1 in, 1 out */
        acc_f += ef[i];
        fg[i] = acc_f;
    }
    for (i = 0; i < 160u; i++) sum = sum * 31u + fg[i];
    hw_checksum = sum;
}
