/* EasyLab AVR driver "line_camera": a line-following camera module on a
 * UART (the device's uart[n] claim), 115200 baud 8N1.
 *
 * The module sends the line's position whenever it has a new image, in
 * frames of four bytes (docs/boards.md, "Line camera protocol"):
 *
 *     0xA5  LO  HI  CHK       offset = (int16)(HI << 8 | LO), -100..100
 *                             CHK = 0xA5 ^ LO ^ HI
 *
 * read() parses every byte received since the last read and gives the
 * offset of the last good frame (0 until the first one): frames with a bad
 * check byte are dropped and the parser resynchronises on the next 0xA5.
 * The board only listens; the module needs no command. */
#ifndef EL_DRV_LINE_CAMERA_H
#define EL_DRV_LINE_CAMERA_H

#include "avr_internal.h"
#include "el_driver.h"

#ifndef EL_DRV_LINE_CAMERA_BAUD
#define EL_DRV_LINE_CAMERA_BAUD 115200UL
#endif
#define EL_DRV_LINE_CAMERA_SYNC 0xA5u

typedef struct {
    uint8_t got;     /* bytes of the current frame so far (0: waiting for SYNC) */
    uint8_t lo, hi;
    int16_t latest;  /* offset of the last good frame */
    uint16_t bad;    /* frames dropped (saturating) */
} el_drv_line_camera_state_t;

typedef struct {
    uint8_t uart;
    el_drv_line_camera_state_t *state;
    int16_t *offset; /* `out int16` */
} el_drv_line_camera_t;

static inline void el_drv_line_camera_open(const el_drv_line_camera_t *d)
{
    d->state->got = 0u;
    d->state->latest = 0;
    el_avr_uart_open(d->uart, EL_DRV_LINE_CAMERA_BAUD, EL_AVR_PARITY_NONE);
}

EL_DRV_NOTHING(el_drv_line_camera_start, el_drv_line_camera_t)

static inline void el_drv_line_camera_read(const el_drv_line_camera_t *d)
{
    el_drv_line_camera_state_t *s = d->state;
    int16_t c;
    while ((c = el_avr_uart_getc(d->uart)) >= 0) {
        uint8_t b = (uint8_t)c;
        switch (s->got) {
        case 0u:
            if (b == EL_DRV_LINE_CAMERA_SYNC) {
                s->got = 1u;
            }
            break;
        case 1u:
            s->lo = b;
            s->got = 2u;
            break;
        case 2u:
            s->hi = b;
            s->got = 3u;
            break;
        default:
            if (b == (uint8_t)(EL_DRV_LINE_CAMERA_SYNC ^ s->lo ^ s->hi)) {
                s->latest = (int16_t)(uint16_t)((uint16_t)s->hi << 8 | s->lo);
                s->got = 0u;
            } else {
                if (s->bad != 0xFFFFu) {
                    s->bad++;
                }
                s->got = b == EL_DRV_LINE_CAMERA_SYNC ? 1u : 0u;
            }
            break;
        }
    }
    *d->offset = s->latest;
}

EL_DRV_NOTHING(el_drv_line_camera_write, el_drv_line_camera_t)
EL_DRV_NOTHING(el_drv_line_camera_stop, el_drv_line_camera_t)
EL_DRV_NOTHING(el_drv_line_camera_close, el_drv_line_camera_t)

#endif /* EL_DRV_LINE_CAMERA_H */
