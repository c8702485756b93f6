/* EasyLab AVR board: declarations shared by the board's own files
 * (avr_port.c, avr_uart.c, avr_nv.c, avr_interfaces.c, the drivers).
 * Generated code includes el_board.h, never this.
 *
 * el_avr_config.h is generated for each build (the board's backend, devices.py): the
 * MCU, the tick timer's settings, the UARTs the model uses and their ring
 * sizes, the debug and Modbus UARTs, the watchdog, EL_AVR_SIM.
 */
#ifndef AVR_INTERNAL_H
#define AVR_INTERNAL_H

#include "el_types.h"
#include "el_avr_config.h"

#include <avr/io.h>
#include <avr/interrupt.h>

#if EL_AVR_CONFIG_VERSION != 1
#error "el_avr_config.h was generated for another version of the AVR board: rebuild"
#endif

/* ---- time (avr_port.c) ---- */

/* The fine clock: Timer2 clock periods (F_CPU / EL_AVR_TICK_PRESCALE) since
 * boot, wrapping at 2^32 (about 37 minutes with a prescaler of 32, 4.9 h with
 * 128). Callable with interrupts on or off. */
uint32_t el_avr_clock(void);

/* Fine-clock periods in `us` microseconds (rounded up). */
uint32_t el_avr_clock_from_us(uint32_t us);

/* ---- UARTs (avr_uart.c): interrupt-driven rings, 8 data bits, 1 stop bit ---- */

#define EL_AVR_PARITY_NONE 0u
#define EL_AVR_PARITY_EVEN 1u
#define EL_AVR_PARITY_ODD 2u

/* Configure USART n (a UART the model uses: el_avr_config.h has its rings)
 * and enable its receiver, transmitter and receive interrupt: `ubrr` the
 * baud rate divisor in double speed, `frame` UCSRnC. False: UART n is not
 * in use. */
bool el_avr_uart_setup(uint8_t n, uint16_t ubrr, uint8_t frame);
/* el_avr_uart_setup with 8 data bits, 1 stop bit, `parity` and the nearest
 * divisor of `baud` (a constant baud rate costs no division at run time). */
static inline void el_avr_uart_open(uint8_t n, uint32_t baud, uint8_t parity)
{
    uint8_t frame = (uint8_t)(_BV(UCSZ01) | _BV(UCSZ00));
    if (baud == 0u) {
        return;
    }
    if (parity == EL_AVR_PARITY_EVEN) {
        frame |= _BV(UPM01);
    } else if (parity == EL_AVR_PARITY_ODD) {
        frame |= (uint8_t)(_BV(UPM01) | _BV(UPM00));
    }
    (void)el_avr_uart_setup(n, (uint16_t)((F_CPU + 4u * baud) / (8u * baud) - 1u), frame);
}
/* The next received byte, or -1. */
int16_t el_avr_uart_getc(uint8_t n);
/* Bytes waiting in the receive ring. */
uint8_t el_avr_uart_available(uint8_t n);
/* Take up to `max` received bytes; returns how many. On a UART without a
 * transmit ring (EL_AVR_UARTn_TX 0: the debug UART), none while a write
 * is still going out, and none after a zero byte (a COBS frame's end). */
uint16_t el_avr_uart_read(uint8_t n, uint8_t *buf, uint16_t max);
/* Queue `len` bytes for sending: all of them (waiting about `wait_ms`, or
 * longer under interrupts, for room in the ring while the ring drains), or
 * none (false). A UART without a transmit ring sends from `data` itself
 * (1 to 255 bytes), which must stay as it is until a read of that UART
 * returns bytes again; it never waits, and refuses a write while one goes
 * out. */
bool el_avr_uart_write(uint8_t n, const uint8_t *data, uint16_t len, uint16_t wait_ms);
/* The fine clock (el_avr_clock) when the Modbus UART (EL_AVR_MODBUS_UART)
 * last received a byte. */
uint32_t el_avr_uart_last_rx(void);

/* ---- the I2C bus (avr_twi.c; runtime_c/el_bus.h) ---- */

/* Try a job parked on a busy chip again; the tick's timer interrupt calls
 * it when the model has devices on the bus (EL_AVR_I2C). */
void el_avr_twi_poll(void);

/* ---- the ADC (avr_port.c) ---- */

/* Enable the ADC (AVCC reference, clock F_CPU / 128) and disconnect the
 * digital input of channel `ch`'s pin. */
void el_avr_adc_open(uint8_t ch);
/* One 10-bit conversion of channel `ch` (busy-waits about 104 us). */
uint16_t el_avr_adc_read(uint8_t ch);

/* ---- simulation hooks (EL_AVR_SIM builds, avr_port.c; docs/boards.md) ---- */

/* Written to GPIOR0 (the harness hooks writes to it). */
#define EL_AVR_SIM_INPUTS 1u   /* el_port_inputs: apply the stimulus due now */
#define EL_AVR_SIM_INSTANT 2u  /* el_port_instant: record the instant */
#define EL_AVR_SIM_REPORT 3u   /* a test program's result byte follows in GPIOR1 */

#endif /* AVR_INTERNAL_H */
