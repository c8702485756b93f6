/* EasyLab f16 board: the drivers of std's devices on the MB90F543.
 *
 * A device is a constant description (generated el_f16_devices.c) that
 * generated code hands to its driver's handlers,
 * el_drv_<driver>_<open|start|read|write|stop|close>(&el_dev<id>). The
 * handlers are functions (f16_drivers.c): C89 has no inline, and a static
 * function a file does not call is a warning there.
 */
#ifndef EL_F16_DRIVERS_H
#define EL_F16_DRIVERS_H

#include "el_types.h"

/* AnalogIn, Pt100: one 10-bit conversion of channel ANn at each read. */
typedef struct {
    uint8_t channel;
    uint16_t *value;
} el_drv_analog_in_t;

/* DigitalIn, DigitalOut: one pin, `mask` in port `port` (PDRn, DDRn). */
typedef struct {
    uint8_t port;
    uint8_t mask;
    bool *level;
} el_drv_digital_t;
typedef el_drv_digital_t el_drv_digital_in_t;
typedef el_drv_digital_t el_drv_digital_out_t;

/* PwmOut: PPG channel `channel` in 8-bit mode, 256 counts of the machine
 * clock / 16 (3.9 kHz at 16 MHz); duty 0..255 (clamped) is the high time
 * in counts; 0 turns the pulse off and holds the pin (`port`, `mask`) low. */
typedef struct {
    uint8_t channel;
    uint8_t port;
    uint8_t mask;
    int16_t *duty;
} el_drv_pwm_out_t;

/* Motor: |speed| (-255..255, clamped) as the PPG duty, the sign on the
 * direction pin (high: negative). */
typedef struct {
    el_drv_pwm_out_t pwm;
    uint8_t dir_port;
    uint8_t dir_mask;
    int16_t *speed;
} el_drv_motor_t;

/* Encoder: 4x quadrature decoding in the external interrupts of both pins
 * (INTn, each armed for the edge that comes next); read copies the count. */
typedef struct {
    volatile int32_t position;
    volatile uint8_t last; /* A << 1 | B */
} el_drv_encoder_state_t;
typedef struct {
    uint8_t port_a;
    uint8_t mask_a;
    uint8_t int_a; /* INTn of pin A */
    uint8_t port_b;
    uint8_t mask_b;
    uint8_t int_b;
    el_drv_encoder_state_t *state;
    int32_t *count;
} el_drv_encoder_t;

#define EL_F16_DRIVER_HANDLERS(name)                    \
    void el_drv_##name##_open(const el_drv_##name##_t *d);  \
    void el_drv_##name##_start(const el_drv_##name##_t *d); \
    void el_drv_##name##_read(const el_drv_##name##_t *d);  \
    void el_drv_##name##_write(const el_drv_##name##_t *d); \
    void el_drv_##name##_stop(const el_drv_##name##_t *d);  \
    void el_drv_##name##_close(const el_drv_##name##_t *d);

EL_F16_DRIVER_HANDLERS(analog_in)
EL_F16_DRIVER_HANDLERS(digital_in)
EL_F16_DRIVER_HANDLERS(digital_out)
EL_F16_DRIVER_HANDLERS(pwm_out)
EL_F16_DRIVER_HANDLERS(motor)
EL_F16_DRIVER_HANDLERS(encoder)

/* The encoder's interrupt work (generated interrupt handlers call it). */
void el_drv_encoder_update(const el_drv_encoder_t *d);

#endif /* EL_F16_DRIVERS_H */
