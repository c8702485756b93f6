/* EasyLab PIC18 board: the hardware layer as the portable files see it.
 *
 * Portable C only (no compiler keywords, no registers): the port's
 * portable part (pic18_port.c, pic18_interfaces.c), the drivers
 * (drivers/) and the port contract hooks call these functions, which the
 * hardware files implement (pic18_hw.c, pic18_uart.c, pic18_nv.c).
 * el_pic18_config.h is generated for each build (devices.py): the MCU,
 * the tick timer, the UART's rings, the ADC channels, the watchdog,
 * EL_PIC18_SIM.
 */
#ifndef PIC18_HW_H
#define PIC18_HW_H

#include <stdint.h>
#include <stdbool.h>

#include "el_pic18_config.h"

#if EL_PIC18_CONFIG_VERSION != 1
#error "el_pic18_config.h was generated for another version of the PIC18 board: rebuild"
#endif

/* A port pin: port (0 = A .. 4 = E) << 3 | bit. */
typedef uint8_t el_pic18_pin_t;

/* A pin as the buses take a chip select (runtime_c/el_bus.h's el_pin_t;
 * the backend's chip_select gives its initializer, handler files get it
 * as EL_CS). */
struct el_pin {
    el_pic18_pin_t code;
};

/* ---- start, time, interrupts (pic18_hw.c) ---- */

/* Timers, interrupts and the watchdog on; returns the reset's cause
 * (EL_PIC18_RESET_...). */
uint8_t el_pic18_start(void);
#define EL_PIC18_RESET_POWER 0u    /* power-on or brown-out */
#define EL_PIC18_RESET_WATCHDOG 1u /* the watchdog (a task that kept the CPU too long) */
#define EL_PIC18_RESET_SOFTWARE 2u /* the RESET instruction (the debugger's RESET) */
#define EL_PIC18_RESET_PIN 3u      /* MCLR */

/* LET ticks since el_pic18_start (Timer2's interrupts, counted). */
uint32_t el_pic18_ticks(void);
/* The tick period starts afresh now; the tick counter becomes `tick`. */
void el_pic18_resync(uint32_t tick);
/* The fine clock: instruction cycles (EL_PIC18_FCY per second) since
 * el_pic18_start, wrapping at 2^32 (about 7 minutes at 10 MHz). */
uint32_t el_pic18_clock(void);
/* The same inside the interrupt handler or a critical section (it leaves
 * the interrupt enable alone; builds with the I2C bus). */
uint32_t el_pic18_clock_isr(void);
/* Critical sections: the previous state of the global interrupt enable. */
uint8_t el_pic18_irq_save(void);
void el_pic18_irq_restore(uint8_t state);
bool el_pic18_irq_enabled(void);
void el_pic18_watchdog_kick(void);
/* Restart the MCU now (the RESET instruction). */
void el_pic18_reset(void);
/* Stop for good: interrupts off, the watchdog off, the CPU asleep. */
void el_pic18_stop(void);

/* A byte that survives a software or watchdog reset (not a power-on), at
 * the last RAM address (pic18_hw.c defines it there). */
#if !defined(EL_PIC18_DEFINES_KEPT)
extern uint8_t el_pic18_kept;
#endif

/* ---- pins, ADC, PWM, encoders (pic18_hw.c) ---- */

void el_pic18_pin_input(el_pic18_pin_t pin);
void el_pic18_pin_output(el_pic18_pin_t pin); /* low first */
bool el_pic18_pin_read(el_pic18_pin_t pin);
void el_pic18_pin_write(el_pic18_pin_t pin, bool level);

void el_pic18_adc_open(uint8_t channel);
uint16_t el_pic18_adc_read(uint8_t channel); /* 10 bits, Vdd reference */

/* CCP module 1 or 2 as PWM on Timer2 (the tick's timer: its period is
 * the PWM period); duty 0..255 (0: low, 255: high all the time). */
void el_pic18_pwm_open(uint8_t ccp);
void el_pic18_pwm_set(uint8_t ccp, uint8_t duty);

/* Quadrature encoder slot `slot` (< EL_PIC18_ENCODERS) on two interrupt
 * pins; its count, read atomically. */
void el_pic18_encoder_open(uint8_t slot, el_pic18_pin_t a, el_pic18_pin_t b);
int32_t el_pic18_encoder_count(uint8_t slot);

/* ---- the EUSART (pic18_uart.c): interrupt-driven rings, 8 data bits,
 * parity in a 9th bit, 1 stop bit ---- */

#define EL_PIC18_PARITY_NONE 0u
#define EL_PIC18_PARITY_EVEN 1u
#define EL_PIC18_PARITY_ODD 2u

void el_pic18_uart_open(uint32_t baud, uint8_t parity);
int16_t el_pic18_uart_getc(void);           /* the next byte, or -1 */
uint8_t el_pic18_uart_available(void);
uint16_t el_pic18_uart_read(uint8_t *buf, uint16_t max);
/* Queue all `len` bytes (waiting at most `wait_ms` for room while the ring
 * drains), or none (false). */
bool el_pic18_uart_write(const uint8_t *data, uint16_t len, uint16_t wait_ms);
uint32_t el_pic18_uart_last_rx(void);       /* the fine clock at the last byte received */
uint16_t el_pic18_uart_errors(void);        /* framing, parity, overrun, full ring (saturating) */
/* Polled output for programs without the ring (the port contract program). */
void el_pic18_uart_putc_polled(uint8_t c);
void el_pic18_uart_flush_polled(void);

/* ---- the MSSP as the I2C master (pic18_mssp.c): the interrupt
 * handler's part, for SSPIF and BCLIF, and for a tick's interrupt while a
 * job waits parked for its busy chip ---- */

void el_pic18_i2c_isr(void);
extern volatile bool el_pic18_i2c_parked;

/* ---- data EEPROM (pic18_nv.c) ---- */

uint8_t el_pic18_eeprom_read(uint16_t address);
/* Program one byte when it differs (about 4 ms; the watchdog is kicked). */
void el_pic18_eeprom_update(uint16_t address, uint8_t value);

/* ---- simulation builds (EL_PIC18_SIM): instants reported to the gpsim
 * harness through a byte it watches (pic18_port.c) ---- */

#define EL_PIC18_SIM_INPUTS 1u  /* el_port_inputs: apply the stimulus due now */
#define EL_PIC18_SIM_INSTANT 2u /* el_port_instant: record the instant */
#define EL_PIC18_SIM_BOOT 3u    /* el_port_init: the firmware (re)started, its RAM cleared */
/* An iteration of a wait loop begins (el_port_wait_tick, el_port_idle): the
 * harness counts them and their shortest span, the bare loop's cost, so
 * that --report can tell the cycles spent waiting from the CPU's work (the
 * PIC18 polls where the AVR sleeps). */
#define EL_PIC18_SIM_WAIT 4u
#define EL_PIC18_SIM_IDLE 5u
#define EL_PIC18_SIM_HALT 0xA5u /* el_pic18_sim_busy at start: the harness's --halt */

#endif /* PIC18_HW_H */
