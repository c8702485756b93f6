/* EasyLab f16 board: the device drivers (drivers/el_f16_drivers.h) on the
 * MB90F543's ports, A/D converter, PPG timers and external interrupts
 * (mb90f543_regs.h). Handlers a driver has no use for do nothing. */
#include "el_f16_drivers.h"
#include "el_port.h"
#include "mb90f543_regs.h"

#define PPG_COUNTS 256u

/* ---- AnalogIn ---- */

void el_drv_analog_in_open(const el_drv_analog_in_t *d)
{
    /* The pin of ANn is port 5's bit n: analog input, not an output. */
    EL_F16_DDR(5u) = (uint8_t)(EL_F16_DDR(5u) & (uint8_t)~(1u << d->channel));
    EL_F16_ADER = (uint8_t)(EL_F16_ADER | (uint8_t)(1u << d->channel));
}

void el_drv_analog_in_start(const el_drv_analog_in_t *d)
{
    (void)d;
}

void el_drv_analog_in_read(const el_drv_analog_in_t *d)
{
    /* One conversion of the channel alone (start = end channel), started by
     * software, with the reset defaults' sampling and compare times. */
    EL_F16_ADCS0 = (uint8_t)((uint8_t)(d->channel << 3) | d->channel);
    EL_F16_ADCS1 = EL_F16_ADCS1_STRT;
    while ((EL_F16_ADCS1 & EL_F16_ADCS1_INT) == 0u) {
    }
    *d->value = (uint16_t)(EL_F16_ADCR & 0x03FFu);
    EL_F16_ADCS1 = 0u; /* clears INT */
}

void el_drv_analog_in_write(const el_drv_analog_in_t *d)
{
    (void)d;
}

void el_drv_analog_in_stop(const el_drv_analog_in_t *d)
{
    (void)d;
}

void el_drv_analog_in_close(const el_drv_analog_in_t *d)
{
    (void)d;
}

/* ---- DigitalIn, DigitalOut ---- */

static void pin_set(uint8_t port, uint8_t mask, bool high)
{
    el_irq_state_t state = el_port_irq_save(); /* interrupt handlers write ports too */
    if (high) {
        EL_F16_PDR(port) = (uint8_t)(EL_F16_PDR(port) | mask);
    } else {
        EL_F16_PDR(port) = (uint8_t)(EL_F16_PDR(port) & (uint8_t)~mask);
    }
    el_port_irq_restore(state);
}

static void pin_output(uint8_t port, uint8_t mask, bool output)
{
    el_irq_state_t state = el_port_irq_save();
    if (output) {
        EL_F16_DDR(port) = (uint8_t)(EL_F16_DDR(port) | mask);
    } else {
        EL_F16_DDR(port) = (uint8_t)(EL_F16_DDR(port) & (uint8_t)~mask);
    }
    el_port_irq_restore(state);
}

void el_drv_digital_in_open(const el_drv_digital_in_t *d)
{
    pin_output(d->port, d->mask, false);
}

void el_drv_digital_in_start(const el_drv_digital_in_t *d)
{
    (void)d;
}

void el_drv_digital_in_read(const el_drv_digital_in_t *d)
{
    *d->level = (EL_F16_PDR(d->port) & d->mask) != 0u;
}

void el_drv_digital_in_write(const el_drv_digital_in_t *d)
{
    (void)d;
}

void el_drv_digital_in_stop(const el_drv_digital_in_t *d)
{
    (void)d;
}

void el_drv_digital_in_close(const el_drv_digital_in_t *d)
{
    (void)d;
}

void el_drv_digital_out_open(const el_drv_digital_out_t *d)
{
    pin_set(d->port, d->mask, false);
    pin_output(d->port, d->mask, true);
}

void el_drv_digital_out_start(const el_drv_digital_out_t *d)
{
    (void)d;
}

void el_drv_digital_out_read(const el_drv_digital_out_t *d)
{
    (void)d;
}

void el_drv_digital_out_write(const el_drv_digital_out_t *d)
{
    pin_set(d->port, d->mask, *d->level);
}

void el_drv_digital_out_stop(const el_drv_digital_out_t *d)
{
    (void)d;
}

void el_drv_digital_out_close(const el_drv_digital_out_t *d)
{
    pin_set(d->port, d->mask, false);
}

/* ---- PwmOut ---- */

static void ppg_duty(const el_drv_pwm_out_t *d, int16_t duty)
{
    uint8_t ch = d->channel;
    uint8_t reserved = (ch % 2u) == 0u ? EL_F16_PPGC_EVEN_RESERVED : EL_F16_PPGC_ODD_RESERVED;
    if (duty <= 0) {
        /* Off: the port drives the pin low, the channel stops. */
        pin_set(d->port, d->mask, false);
        EL_F16_PPGC(ch) = reserved;
        return;
    }
    if (duty > 255) {
        duty = 255;
    }
    EL_F16_PRLH(ch) = (uint8_t)(duty - 1);                  /* high for `duty` counts */
    EL_F16_PRLL(ch) = (uint8_t)(PPG_COUNTS - 1u - (uint16_t)duty); /* low for the rest */
    EL_F16_PPGC(ch) = (uint8_t)(reserved | EL_F16_PPGC_PEN | EL_F16_PPGC_PE);
}

void el_drv_pwm_out_open(const el_drv_pwm_out_t *d)
{
    EL_F16_PPG_CLK(d->channel) = EL_F16_PPG_CLK_DIV16;
    pin_set(d->port, d->mask, false);
    pin_output(d->port, d->mask, true);
    ppg_duty(d, 0);
}

void el_drv_pwm_out_start(const el_drv_pwm_out_t *d)
{
    (void)d;
}

void el_drv_pwm_out_read(const el_drv_pwm_out_t *d)
{
    (void)d;
}

void el_drv_pwm_out_write(const el_drv_pwm_out_t *d)
{
    ppg_duty(d, *d->duty);
}

void el_drv_pwm_out_stop(const el_drv_pwm_out_t *d)
{
    ppg_duty(d, 0);
}

void el_drv_pwm_out_close(const el_drv_pwm_out_t *d)
{
    ppg_duty(d, 0);
}

/* ---- Motor ---- */

void el_drv_motor_open(const el_drv_motor_t *d)
{
    el_drv_pwm_out_open(&d->pwm);
    pin_set(d->dir_port, d->dir_mask, false);
    pin_output(d->dir_port, d->dir_mask, true);
}

void el_drv_motor_start(const el_drv_motor_t *d)
{
    (void)d;
}

void el_drv_motor_read(const el_drv_motor_t *d)
{
    (void)d;
}

void el_drv_motor_write(const el_drv_motor_t *d)
{
    int16_t speed = *d->speed;
    pin_set(d->dir_port, d->dir_mask, speed < 0);
    ppg_duty(&d->pwm, speed < 0 ? (int16_t)(speed < -255 ? 255 : -speed) : speed);
}

void el_drv_motor_stop(const el_drv_motor_t *d)
{
    ppg_duty(&d->pwm, 0);
}

void el_drv_motor_close(const el_drv_motor_t *d)
{
    ppg_duty(&d->pwm, 0);
}

/* ---- Encoder ---- */

/* Arm INTn for the edge that comes next: rising while the pin is low. */
static void arm_edge(uint8_t intn, bool pin_high)
{
    uint16_t shift = (uint16_t)(2u * intn);
    uint16_t edge = pin_high ? EL_F16_ELVR_FALLING : EL_F16_ELVR_RISING;
    EL_F16_ELVR = (uint16_t)((EL_F16_ELVR & (uint16_t)~(3u << shift)) | (uint16_t)(edge << shift));
}

static uint8_t encoder_pins(const el_drv_encoder_t *d)
{
    return (uint8_t)(((EL_F16_PDR(d->port_a) & d->mask_a) != 0u ? 2u : 0u) |
                     ((EL_F16_PDR(d->port_b) & d->mask_b) != 0u ? 1u : 0u));
}

void el_drv_encoder_update(const el_drv_encoder_t *d)
{
    /* (last << 2 | now): +1 going forward (A leads B: 0, 2, 3, 1), -1 back,
     * 0 for no change or a skipped state. */
    static const int8_t step[16] = {0, -1, 1, 0, 1, 0, 0, -1, -1, 0, 0, 1, 0, 1, -1, 0};
    uint8_t now = encoder_pins(d);
    EL_F16_EIRR = (uint8_t)(EL_F16_EIRR & (uint8_t)~((1u << d->int_a) | (1u << d->int_b)));
    d->state->position += step[(uint8_t)(d->state->last << 2) | now];
    d->state->last = now;
    arm_edge(d->int_a, (now & 2u) != 0u);
    arm_edge(d->int_b, (now & 1u) != 0u);
}

void el_drv_encoder_open(const el_drv_encoder_t *d)
{
    el_irq_state_t state;
    pin_output(d->port_a, d->mask_a, false);
    pin_output(d->port_b, d->mask_b, false);
    state = el_port_irq_save();
    d->state->position = 0;
    d->state->last = encoder_pins(d);
    arm_edge(d->int_a, (d->state->last & 2u) != 0u);
    arm_edge(d->int_b, (d->state->last & 1u) != 0u);
    EL_F16_EIRR = (uint8_t)(EL_F16_EIRR & (uint8_t)~((1u << d->int_a) | (1u << d->int_b)));
    EL_F16_ENIR = (uint8_t)(EL_F16_ENIR | (uint8_t)((1u << d->int_a) | (1u << d->int_b)));
    el_port_irq_restore(state);
}

void el_drv_encoder_start(const el_drv_encoder_t *d)
{
    (void)d;
}

void el_drv_encoder_read(const el_drv_encoder_t *d)
{
    el_irq_state_t state = el_port_irq_save();
    *d->count = d->state->position;
    el_port_irq_restore(state);
}

void el_drv_encoder_write(const el_drv_encoder_t *d)
{
    (void)d;
}

void el_drv_encoder_stop(const el_drv_encoder_t *d)
{
    (void)d;
}

void el_drv_encoder_close(const el_drv_encoder_t *d)
{
    EL_F16_ENIR = (uint8_t)(EL_F16_ENIR & (uint8_t)~((1u << d->int_a) | (1u << d->int_b)));
}
