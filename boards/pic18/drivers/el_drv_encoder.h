/* EasyLab PIC18 driver "encoder" (std's Encoder): a quadrature encoder on
 * two pins that can interrupt: RB0..RB2 (INT0..INT2, the sensed edge
 * switched at each interrupt, so both edges count) or RB4..RB7 (PORTB's
 * interrupt on change). The interrupt counts in 4x resolution (+1 per edge
 * when A leads B, -1 when B leads A; an impossible transition counts
 * nothing: pic18_hw.c); read() copies the int32 count atomically into the
 * device's `out int32` datum. The pins are inputs without pull-ups. */
#ifndef EL_DRV_ENCODER_H
#define EL_DRV_ENCODER_H

#include "pic18_hw.h"
#include "el_driver.h"

typedef struct {
    uint8_t slot; /* the hardware's encoder slot (< EL_PIC18_ENCODERS) */
    el_pic18_pin_t a, b;
    int32_t *count; /* `out int32` */
} el_drv_encoder_t;

static inline void el_drv_encoder_open(const el_drv_encoder_t *d)
{
    el_pic18_encoder_open(d->slot, d->a, d->b);
}

EL_DRV_NOTHING(el_drv_encoder_start, el_drv_encoder_t)

static inline void el_drv_encoder_read(const el_drv_encoder_t *d)
{
    *d->count = el_pic18_encoder_count(d->slot);
}

EL_DRV_NOTHING(el_drv_encoder_write, el_drv_encoder_t)
EL_DRV_NOTHING(el_drv_encoder_stop, el_drv_encoder_t)
EL_DRV_NOTHING(el_drv_encoder_close, el_drv_encoder_t)

#endif /* EL_DRV_ENCODER_H */
