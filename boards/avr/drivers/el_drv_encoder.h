/* EasyLab AVR driver "encoder" (std's Encoder): a quadrature encoder on
 * two pins with pin-change or external interrupts (INTn, any edge).
 *
 * Every edge of A or B runs el_drv_encoder_update (from the interrupt
 * handlers generated in el_avr_devices.c), which counts in 4x resolution:
 * +1 per edge when A leads B, -1 when B leads A; an impossible transition
 * (both pins changed between two interrupts) counts nothing. read() copies
 * the count (int32) atomically into the device's `out int32` datum. The
 * pins are inputs without pull-ups. */
#ifndef EL_DRV_ENCODER_H
#define EL_DRV_ENCODER_H

#include "avr_internal.h"
#include "el_driver.h"
#include "el_drv_digital.h"

#include <util/atomic.h>

typedef struct {
    volatile int32_t count;
    volatile uint8_t last; /* A << 1 | B at the last interrupt */
} el_drv_encoder_state_t;

typedef struct {
    volatile uint8_t *pin_a; /* PINx */
    uint8_t mask_a;
    volatile uint8_t *pin_b;
    uint8_t mask_b;
    el_drv_encoder_state_t *state;
    void (*irq_on)(void);    /* generated: enables the pins' interrupts */
    int32_t *count;          /* `out int32` */
} el_drv_encoder_t;

/* Index: previous A B << 2 | new A B. */
static const int8_t el_drv_encoder_steps[16] EL_ROM = {0, -1, 1, 0, 1, 0, 0, -1, -1, 0, 0, 1, 0, 1, -1, 0};

static inline uint8_t el_drv_encoder_ab(const el_drv_encoder_t *d)
{
    return (uint8_t)(((*d->pin_a & d->mask_a) != 0u ? 2u : 0u) | ((*d->pin_b & d->mask_b) != 0u ? 1u : 0u));
}

/* From the pins' interrupt handlers. */
static inline void el_drv_encoder_update(const el_drv_encoder_t *d)
{
    uint8_t ab = el_drv_encoder_ab(d);
    uint8_t last = d->state->last;
    if (ab != last) {
        d->state->count += (int8_t)EL_ROM_READ_U8(&el_drv_encoder_steps[(uint8_t)(last << 2) | ab]);
        d->state->last = ab;
    }
}

static inline void el_drv_encoder_open(const el_drv_encoder_t *d)
{
    *EL_AVR_DDR(d->pin_a) &= (uint8_t)~d->mask_a;
    *EL_AVR_PORT(d->pin_a) &= (uint8_t)~d->mask_a;
    *EL_AVR_DDR(d->pin_b) &= (uint8_t)~d->mask_b;
    *EL_AVR_PORT(d->pin_b) &= (uint8_t)~d->mask_b;
    ATOMIC_BLOCK(ATOMIC_RESTORESTATE) {
        d->state->count = 0;
        d->state->last = el_drv_encoder_ab(d);
        d->irq_on();
    }
}

EL_DRV_NOTHING(el_drv_encoder_start, el_drv_encoder_t)

static inline void el_drv_encoder_read(const el_drv_encoder_t *d)
{
    int32_t n;
    ATOMIC_BLOCK(ATOMIC_RESTORESTATE) {
        n = d->state->count;
    }
    *d->count = n;
}

EL_DRV_NOTHING(el_drv_encoder_write, el_drv_encoder_t)
EL_DRV_NOTHING(el_drv_encoder_stop, el_drv_encoder_t)
EL_DRV_NOTHING(el_drv_encoder_close, el_drv_encoder_t)

#endif /* EL_DRV_ENCODER_H */
