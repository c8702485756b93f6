/* EasyLab AVR drivers "pwm_out" (std's PwmOut) and "motor" (std's Motor).
 *
 * PWM: the pin's timer in 8-bit fast PWM mode at F_CPU / 64 / 256 (977 Hz
 * at 16 MHz), non-inverting. A duty of 0 disconnects the compare output and
 * drives the pin low (fast PWM would leave a one-count spike); 1..255 is
 * the compare value (255: always high). pwm_out clamps its `in int16` duty
 * to 0..255. motor: speed -255..255, |speed| (clamped) as the duty and
 * the sign on the direction pin (high when negative). */
#ifndef EL_DRV_PWM_H
#define EL_DRV_PWM_H

#include "avr_internal.h"
#include "el_driver.h"
#include "el_drv_digital.h"

typedef struct {
    volatile uint8_t *tccra; /* TCCRnA; TCCRnB follows */
    volatile uint8_t *ocr;   /* OCRnx; for a 16-bit timer its low byte, the high byte follows */
    uint8_t com;             /* COMnx1 in TCCRnA */
    uint8_t wide;            /* a 16-bit timer */
    volatile uint8_t *pin;   /* PINx of the output pin */
    uint8_t mask;
    int16_t *duty;           /* `in int16` (pwm_out) */
} el_drv_pwm_out_t;

typedef struct {
    el_drv_pwm_out_t pwm;
    volatile uint8_t *dir;   /* PINx of the direction pin */
    uint8_t dir_mask;
    int16_t *speed;          /* `in int16` */
} el_drv_motor_t;

static inline void el_drv_pwm_setup(const el_drv_pwm_out_t *d)
{
    *EL_AVR_PORT(d->pin) &= (uint8_t)~d->mask;
    *EL_AVR_DDR(d->pin) |= d->mask;
    if (d->wide) {
        d->tccra[0] |= _BV(WGM10);                                    /* mode 5: fast PWM, 8-bit */
        d->tccra[1] = (uint8_t)(_BV(WGM12) | _BV(CS11) | _BV(CS10)); /* clk / 64 */
    } else {
        d->tccra[0] |= (uint8_t)(_BV(WGM01) | _BV(WGM00));           /* mode 3: fast PWM */
        d->tccra[1] = (uint8_t)(_BV(CS01) | _BV(CS00));              /* clk / 64 */
    }
}

static inline void el_drv_pwm_set(const el_drv_pwm_out_t *d, uint8_t duty)
{
    if (duty == 0u) {
        d->tccra[0] &= (uint8_t)~d->com;
        *EL_AVR_PORT(d->pin) &= (uint8_t)~d->mask;
        return;
    }
    if (d->wide) {
        d->ocr[1] = 0u; /* high byte first (through TEMP) */
    }
    d->ocr[0] = duty;
    d->tccra[0] |= d->com;
}

static inline uint8_t el_drv_pwm_clamp(int16_t v)
{
    return v <= 0 ? 0u : (v >= 255 ? 255u : (uint8_t)v);
}

static inline void el_drv_pwm_out_open(const el_drv_pwm_out_t *d)
{
    el_drv_pwm_setup(d);
}

EL_DRV_NOTHING(el_drv_pwm_out_start, el_drv_pwm_out_t)
EL_DRV_NOTHING(el_drv_pwm_out_read, el_drv_pwm_out_t)

static inline void el_drv_pwm_out_write(const el_drv_pwm_out_t *d)
{
    el_drv_pwm_set(d, el_drv_pwm_clamp(*d->duty));
}

static inline void el_drv_pwm_out_stop(const el_drv_pwm_out_t *d)
{
    el_drv_pwm_set(d, 0u);
}

EL_DRV_NOTHING(el_drv_pwm_out_close, el_drv_pwm_out_t)

static inline void el_drv_motor_open(const el_drv_motor_t *d)
{
    *EL_AVR_PORT(d->dir) &= (uint8_t)~d->dir_mask;
    *EL_AVR_DDR(d->dir) |= d->dir_mask;
    el_drv_pwm_setup(&d->pwm);
}

EL_DRV_NOTHING(el_drv_motor_start, el_drv_motor_t)
EL_DRV_NOTHING(el_drv_motor_read, el_drv_motor_t)

static inline void el_drv_motor_write(const el_drv_motor_t *d)
{
    int16_t s = *d->speed;
    if (s < 0) {
        *EL_AVR_PORT(d->dir) |= d->dir_mask;
        el_drv_pwm_set(&d->pwm, s < -255 ? 255u : (uint8_t)(-s));
    } else {
        *EL_AVR_PORT(d->dir) &= (uint8_t)~d->dir_mask;
        el_drv_pwm_set(&d->pwm, el_drv_pwm_clamp(s));
    }
}

static inline void el_drv_motor_stop(const el_drv_motor_t *d)
{
    el_drv_pwm_set(&d->pwm, 0u);
}

EL_DRV_NOTHING(el_drv_motor_close, el_drv_motor_t)

#endif /* EL_DRV_PWM_H */
