/* EasyLab fuzz targets: what every target asks of a frame the firmware
 * sends (the debug server's and the remote proxy's links share the
 * framing: COBS, one 0x00 at the end, CRC-16 of the decoded bytes). */
#ifndef FUZZ_FRAMES_H
#define FUZZ_FRAMES_H

#include "el_crc16.h"
#include "el_debug_cobs.h"

#include <stdlib.h>

/* Decodes a whole sent frame into `out` (`cap` bytes) and returns its
 * length; aborts (a finding) unless it is one well-formed frame of at least
 * `min_len` bytes with a good CRC. */
static uint16_t fuzz_sent_frame(const uint8_t *frame, uint16_t len, uint8_t *out, uint16_t cap, uint16_t min_len)
{
    el_cobs_decoder_t dec;
    uint16_t i;
    uint8_t r = EL_COBS_MORE;
    el_cobs_decoder_init(&dec, out, cap);
    if (len < 2u || frame[len - 1u] != 0u) {
        abort();
    }
    for (i = 0u; i < len; i++) {
        r = el_cobs_decode_byte(&dec, frame[i]);
        if (i + 1u < len && r != EL_COBS_MORE) {
            abort(); /* a 0x00 inside the frame */
        }
    }
    if (r != EL_COBS_FRAME || dec.len < min_len || el_crc16(out, dec.len) != 0u) {
        abort();
    }
    return dec.len;
}

#endif /* FUZZ_FRAMES_H */
