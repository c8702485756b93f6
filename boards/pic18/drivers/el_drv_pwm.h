/* EasyLab PIC18 drivers "pwm_out" (std's PwmOut) and "motor" (std's Motor)
 * on the CCP modules' PWM: CCP1 on RC2, CCP2 on RC1. The period is
 * Timer2's, which also makes the LET tick (hw_map.json gives the
 * frequency: 10 kHz for ticks that are multiples of 100 us); the duty
 * 0..255 maps onto the 10-bit compare value (0: low all the time, 255:
 * high all the time). pwm_out clamps its `in int16` duty to 0..255. motor:
 * speed -255..255, |speed| (clamped) as the duty and the sign on the
 * direction pin (high when negative). */
#ifndef EL_DRV_PWM_H
#define EL_DRV_PWM_H

#include "pic18_hw.h"
#include "el_driver.h"

typedef struct {
    uint8_t ccp;   /* 1 or 2 */
    int16_t *duty; /* `in int16` */
} el_drv_pwm_out_t;

typedef struct {
    uint8_t ccp;
    el_pic18_pin_t dir; /* the direction pin */
    int16_t *speed;     /* `in int16` */
} el_drv_motor_t;

static inline uint8_t el_drv_pwm_clamp(int16_t v)
{
    return v <= 0 ? 0u : (v >= 255 ? 255u : (uint8_t)v);
}

static inline void el_drv_pwm_out_open(const el_drv_pwm_out_t *d)
{
    el_pic18_pwm_open(d->ccp);
}

EL_DRV_NOTHING(el_drv_pwm_out_start, el_drv_pwm_out_t)
EL_DRV_NOTHING(el_drv_pwm_out_read, el_drv_pwm_out_t)

static inline void el_drv_pwm_out_write(const el_drv_pwm_out_t *d)
{
    el_pic18_pwm_set(d->ccp, el_drv_pwm_clamp(*d->duty));
}

static inline void el_drv_pwm_out_stop(const el_drv_pwm_out_t *d)
{
    el_pic18_pwm_set(d->ccp, 0u);
}

EL_DRV_NOTHING(el_drv_pwm_out_close, el_drv_pwm_out_t)

static inline void el_drv_motor_open(const el_drv_motor_t *d)
{
    el_pic18_pin_output(d->dir);
    el_pic18_pwm_open(d->ccp);
}

EL_DRV_NOTHING(el_drv_motor_start, el_drv_motor_t)
EL_DRV_NOTHING(el_drv_motor_read, el_drv_motor_t)

static inline void el_drv_motor_write(const el_drv_motor_t *d)
{
    int16_t s = *d->speed;
    el_pic18_pin_write(d->dir, s < 0);
    el_pic18_pwm_set(d->ccp, s < 0 ? (s < -255 ? 255u : (uint8_t)(-s)) : el_drv_pwm_clamp(s));
}

static inline void el_drv_motor_stop(const el_drv_motor_t *d)
{
    el_pic18_pwm_set(d->ccp, 0u);
}

EL_DRV_NOTHING(el_drv_motor_close, el_drv_motor_t)

#endif /* EL_DRV_PWM_H */
