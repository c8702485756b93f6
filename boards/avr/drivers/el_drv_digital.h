/* EasyLab AVR drivers "digital_in" and "digital_out" (std's DigitalIn and
 * DigitalOut) on one port pin.
 *
 * A pin is described by its PINx register and bit mask; DDRx and PORTx
 * follow PINx at +1 and +2 on every port of these parts. digital_in: an
 * input without pull-up (wire a pull-up or pull-down resistor), read at
 * each read(). digital_out: an output, low from open() on, driven at each
 * write() and low again at stop(). */
#ifndef EL_DRV_DIGITAL_H
#define EL_DRV_DIGITAL_H

#include "avr_internal.h"
#include "el_driver.h"

#define EL_AVR_DDR(pin) ((pin) + 1)
#define EL_AVR_PORT(pin) ((pin) + 2)

typedef struct {
    volatile uint8_t *pin; /* PINx */
    uint8_t mask;
    bool *level;           /* `out bool` */
} el_drv_digital_in_t;

typedef struct {
    volatile uint8_t *pin; /* PINx */
    uint8_t mask;
    bool *level;           /* `in bool` */
} el_drv_digital_out_t;

static inline void el_drv_digital_in_open(const el_drv_digital_in_t *d)
{
    *EL_AVR_DDR(d->pin) &= (uint8_t)~d->mask;
    *EL_AVR_PORT(d->pin) &= (uint8_t)~d->mask;
}

EL_DRV_NOTHING(el_drv_digital_in_start, el_drv_digital_in_t)

static inline void el_drv_digital_in_read(const el_drv_digital_in_t *d)
{
    *d->level = (*d->pin & d->mask) != 0u;
}

EL_DRV_NOTHING(el_drv_digital_in_write, el_drv_digital_in_t)
EL_DRV_NOTHING(el_drv_digital_in_stop, el_drv_digital_in_t)
EL_DRV_NOTHING(el_drv_digital_in_close, el_drv_digital_in_t)

static inline void el_drv_digital_out_open(const el_drv_digital_out_t *d)
{
    *EL_AVR_PORT(d->pin) &= (uint8_t)~d->mask;
    *EL_AVR_DDR(d->pin) |= d->mask;
}

EL_DRV_NOTHING(el_drv_digital_out_start, el_drv_digital_out_t)
EL_DRV_NOTHING(el_drv_digital_out_read, el_drv_digital_out_t)

static inline void el_drv_digital_out_write(const el_drv_digital_out_t *d)
{
    if (*d->level) {
        *EL_AVR_PORT(d->pin) |= d->mask;
    } else {
        *EL_AVR_PORT(d->pin) &= (uint8_t)~d->mask;
    }
}

static inline void el_drv_digital_out_stop(const el_drv_digital_out_t *d)
{
    *EL_AVR_PORT(d->pin) &= (uint8_t)~d->mask;
}

EL_DRV_NOTHING(el_drv_digital_out_close, el_drv_digital_out_t)

#endif /* EL_DRV_DIGITAL_H */
