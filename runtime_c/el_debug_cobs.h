/* EasyLab runtime: COBS (consistent overhead byte stuffing) framing.
 *
 * A frame travels as COBS(bytes) followed by one 0x00 delimiter: COBS
 * removes every 0x00 from the frame, so a receiver resynchronises at any
 * 0x00, whatever came before. The overhead is at most 1 + n / 254 bytes
 * (EL_COBS_MAX_ENCODED). The decoder is a byte-at-a-time state machine
 * that writes into a caller's buffer: no heap, bounded work per byte.
 */
#ifndef EL_DEBUG_COBS_H
#define EL_DEBUG_COBS_H

#include "el_types.h"

/* Encoded size of n bytes, without the delimiter. */
#define EL_COBS_MAX_ENCODED(n) ((n) + 1u + (n) / 254u)

/* Results of el_cobs_decode_byte. */
#define EL_COBS_MORE 0u      /* the frame goes on */
#define EL_COBS_FRAME 1u     /* a delimiter ended a well-formed frame (dec->len bytes) */
#define EL_COBS_EMPTY 2u     /* a delimiter with no frame before it (ignore) */
#define EL_COBS_OVERSIZE 3u  /* a delimiter ended a frame longer than the buffer */
#define EL_COBS_BAD 4u       /* a delimiter ended a frame cut inside a block */

typedef struct {
    uint8_t *buf;      /* decoded bytes go here */
    uint16_t cap;      /* size of buf */
    uint16_t len;      /* decoded bytes so far */
    uint8_t left;      /* data bytes left in the current block */
    uint8_t code;      /* code byte of the current block (0: none yet) */
    bool overflow;     /* more than cap bytes: drop at the delimiter */
} el_cobs_decoder_t;

/* Start decoding into buf[cap]. */
void el_cobs_decoder_init(el_cobs_decoder_t *dec, uint8_t *buf, uint16_t cap);

/* Feed one byte from the wire; returns EL_COBS_... After anything but
 * EL_COBS_MORE the decoder is ready for the next frame (dec->len stays
 * valid until the next byte). */
uint8_t el_cobs_decode_byte(el_cobs_decoder_t *dec, uint8_t byte);

/* Encode src[n] into dst[cap], then the 0x00 delimiter. Returns the bytes
 * written, or 0 when dst is too small. */
uint16_t el_cobs_encode(const uint8_t *src, uint16_t n, uint8_t *dst, uint16_t cap);

#endif /* EL_DEBUG_COBS_H */
