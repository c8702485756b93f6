/* EasyLab AVR driver "analog_in" (std's AnalogIn, and Pt100 through it):
 * one 10-bit conversion of the device's ADC channel at each read(),
 * AVCC reference, 0..1023 into its `out uint16` datum. */
#ifndef EL_DRV_ANALOG_IN_H
#define EL_DRV_ANALOG_IN_H

#include "avr_internal.h"
#include "el_driver.h"

typedef struct {
    uint8_t channel;  /* adc[channel] */
    uint16_t *value;  /* the device's `out` datum */
} el_drv_analog_in_t;

static inline void el_drv_analog_in_open(const el_drv_analog_in_t *d)
{
    el_avr_adc_open(d->channel);
}

EL_DRV_NOTHING(el_drv_analog_in_start, el_drv_analog_in_t)

static inline void el_drv_analog_in_read(const el_drv_analog_in_t *d)
{
    *d->value = el_avr_adc_read(d->channel);
}

EL_DRV_NOTHING(el_drv_analog_in_write, el_drv_analog_in_t)
EL_DRV_NOTHING(el_drv_analog_in_stop, el_drv_analog_in_t)
EL_DRV_NOTHING(el_drv_analog_in_close, el_drv_analog_in_t)

#endif /* EL_DRV_ANALOG_IN_H */
