/* EasyLab PIC18 drivers "digital_in" and "digital_out" (std's DigitalIn and
 * DigitalOut) on one port pin. digital_in: an input (no pull-up: wire a
 * pull-up or pull-down resistor), read at each read(). digital_out: an
 * output through the pin's LAT bit, low from open() on, driven at each
 * write() and low again at stop(). */
#ifndef EL_DRV_DIGITAL_H
#define EL_DRV_DIGITAL_H

#include "pic18_hw.h"
#include "el_driver.h"

typedef struct {
    el_pic18_pin_t pin;
    bool *level; /* `out bool` */
} el_drv_digital_in_t;

typedef struct {
    el_pic18_pin_t pin;
    bool *level; /* `in bool` */
} el_drv_digital_out_t;

static inline void el_drv_digital_in_open(const el_drv_digital_in_t *d)
{
    el_pic18_pin_input(d->pin);
}

EL_DRV_NOTHING(el_drv_digital_in_start, el_drv_digital_in_t)

static inline void el_drv_digital_in_read(const el_drv_digital_in_t *d)
{
    *d->level = el_pic18_pin_read(d->pin);
}

EL_DRV_NOTHING(el_drv_digital_in_write, el_drv_digital_in_t)
EL_DRV_NOTHING(el_drv_digital_in_stop, el_drv_digital_in_t)
EL_DRV_NOTHING(el_drv_digital_in_close, el_drv_digital_in_t)

static inline void el_drv_digital_out_open(const el_drv_digital_out_t *d)
{
    el_pic18_pin_output(d->pin);
}

EL_DRV_NOTHING(el_drv_digital_out_start, el_drv_digital_out_t)
EL_DRV_NOTHING(el_drv_digital_out_read, el_drv_digital_out_t)

static inline void el_drv_digital_out_write(const el_drv_digital_out_t *d)
{
    el_pic18_pin_write(d->pin, *d->level);
}

static inline void el_drv_digital_out_stop(const el_drv_digital_out_t *d)
{
    el_pic18_pin_write(d->pin, false);
}

EL_DRV_NOTHING(el_drv_digital_out_close, el_drv_digital_out_t)

#endif /* EL_DRV_DIGITAL_H */
