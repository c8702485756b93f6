/* EasyLab runtime: COBS framing (see el_debug_cobs.h) of the remote link
 * (el_remote.c) and the fuzz harnesses. The debug server codes its frames
 * in place instead (el_debug.c: frames under 254 bytes). A release build
 * leaves it out with the rest of el_debug*.c. */
#include "el_debug_cobs.h"

void el_cobs_decoder_init(el_cobs_decoder_t *dec, uint8_t *buf, uint16_t cap)
{
    dec->buf = buf;
    dec->cap = cap;
    dec->len = 0u;
    dec->left = 0u;
    dec->code = 0u;
    dec->overflow = false;
}

static void cobs_put(el_cobs_decoder_t *dec, uint8_t byte)
{
    if (dec->len < dec->cap) {
        dec->buf[dec->len] = byte;
        dec->len++;
    } else {
        dec->overflow = true;
    }
}

uint8_t el_cobs_decode_byte(el_cobs_decoder_t *dec, uint8_t byte)
{
    uint8_t result;
    if (byte == 0u) {
        if (dec->overflow) {
            result = EL_COBS_OVERSIZE;
        } else if (dec->code == 0u) {
            result = EL_COBS_EMPTY;
        } else if (dec->left != 0u) {
            result = EL_COBS_BAD;
        } else {
            result = EL_COBS_FRAME;
        }
        dec->left = 0u;
        dec->code = 0u;
        dec->overflow = false;
        if (result != EL_COBS_FRAME) {
            dec->len = 0u;
        }
        return result;
    }
    if (dec->code == 0u && dec->left == 0u) {
        dec->len = 0u; /* first byte of a new frame */
    }
    if (dec->left == 0u) {
        /* A new block: the previous one (unless it was a full 254-byte
         * run) stood for its data and a zero. */
        if (dec->code != 0u && dec->code != 0xFFu) {
            cobs_put(dec, 0u);
        }
        dec->code = byte;
        dec->left = (uint8_t)(byte - 1u);
    } else {
        cobs_put(dec, byte);
        dec->left--;
    }
    return EL_COBS_MORE;
}

uint16_t el_cobs_encode(const uint8_t *src, uint16_t n, uint8_t *dst, uint16_t cap)
{
    uint16_t out = 1u;  /* next free byte */
    uint16_t code_at = 0u;
    uint8_t code = 1u;
    uint16_t i;
    if (cap < (uint16_t)(EL_COBS_MAX_ENCODED((uint32_t)n) + 1u) || n > 0xFF00u) {
        return 0u;
    }
    for (i = 0u; i < n; i++) {
        if (src[i] == 0u) {
            dst[code_at] = code;
            code_at = out++;
            code = 1u;
        } else {
            dst[out++] = src[i];
            code++;
            if (code == 0xFFu) {
                dst[code_at] = code;
                code_at = out++;
                code = 1u;
            }
        }
    }
    dst[code_at] = code;
    dst[out++] = 0u;
    return out;
}
