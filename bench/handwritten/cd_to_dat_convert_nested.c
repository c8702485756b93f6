/* Hand-written reference for the benchmark: cd_to_dat's Convert dataflow as
 * a C programmer would write it for a small RAM, interleaving the stages so
 * that only a few tokens wait between them (the nested single-appearance
 * schedule the generator picks by default: 49 x (3 x (src, b), 2 c), then
 * 4 x (7 d, 8 x (e, 5 f)), then the checksum). Its buffers take 1,696
 * bytes where the flat version's take 4,724 (more than a PIC18F4620's
 * RAM). */
#include <stdint.h>

static uint32_t n;
static uint32_t acc_b, acc_c, acc_d, acc_e, acc_f, sum;
static uint32_t bc[6], cd[196], de[56], ef[5], fg[160];

uint32_t hw_checksum;

void hw_convert(void)
{
    uint8_t i, j, k;
    for (i = 0; i < 49u; i++) {
        for (j = 0; j < 3u; j++) {                 /* src, then b: 1 in, 2 out */
            acc_b += ++n;
            bc[2u * j] = acc_b;
            bc[2u * j + 1u] = acc_b + 1u;
        }
        for (j = 0; j < 2u; j++) {                 /* c: 3 in, 2 out */
            for (k = 0; k < 3u; k++) acc_c += bc[3u * j + k];
            for (k = 0; k < 2u; k++) cd[4u * i + 2u * j + k] = acc_c + k;
        }
    }
    for (i = 0; i < 4u; i++) {
        for (j = 0; j < 7u; j++) {                 /* d: 7 in, 8 out */
            for (k = 0; k < 7u; k++) acc_d += cd[49u * i + 7u * j + k];
            for (k = 0; k < 8u; k++) de[8u * j + k] = acc_d + k;
        }
        for (j = 0; j < 8u; j++) {                 /* e: 7 in, 5 out, then f: 1 in, 1 out */
            for (k = 0; k < 7u; k++) acc_e += de[7u * j + k];
            for (k = 0; k < 5u; k++) ef[k] = acc_e + k;
            for (k = 0; k < 5u; k++) {
                acc_f += ef[k];
                fg[40u * i + 5u * j + k] = acc_f;
            }
        }
    }
    for (i = 0; i < 160u; i++) sum = sum * 31u + fg[i];
    hw_checksum = sum;
}
