/* EasyLab PIC18 driver "analog_in" (std's AnalogIn, and Pt100 through it):
 * one 10-bit conversion of the device's channel at each read(), Vdd as
 * the reference, 0..1023 into its `out uint16` datum. The part's ADCON1
 * makes AN0..ANn analog together: the board's check refuses a digital
 * input on a pin that a claimed channel makes analog. */
#ifndef EL_DRV_ANALOG_IN_H
#define EL_DRV_ANALOG_IN_H

#include "pic18_hw.h"
#include "el_driver.h"

typedef struct {
    uint8_t channel;  /* adc[channel] */
    uint16_t *value;  /* the device's `out` datum */
} el_drv_analog_in_t;

static inline void el_drv_analog_in_open(const el_drv_analog_in_t *d)
{
    el_pic18_adc_open(d->channel);
}

EL_DRV_NOTHING(el_drv_analog_in_start, el_drv_analog_in_t)

static inline void el_drv_analog_in_read(const el_drv_analog_in_t *d)
{
    *d->value = el_pic18_adc_read(d->channel);
}

EL_DRV_NOTHING(el_drv_analog_in_write, el_drv_analog_in_t)
EL_DRV_NOTHING(el_drv_analog_in_stop, el_drv_analog_in_t)
EL_DRV_NOTHING(el_drv_analog_in_close, el_drv_analog_in_t)

#endif /* EL_DRV_ANALOG_IN_H */
