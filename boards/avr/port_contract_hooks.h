/* The AVR board's side of the port contract program
 * (tests/boards/port_contract.c, docs/boards.md "Adding a board"): USART0,
 * polled, for the report (the board's UART code is not used); Timer1 free
 * running at F_CPU as the fine clock; SREG's I bit as the interrupt state. */
#ifndef PORT_CONTRACT_HOOKS_H
#define PORT_CONTRACT_HOOKS_H

#include <avr/io.h>
#include "avr_internal.h"

#define PC_NV_SIZE EL_AVR_NV_SIZE
/* CPU cycles on Timer1, 16 bits, wrapping: spans shorter than 4 ms. */
typedef uint16_t pc_clock_t;
#define PC_CLOCK_PER_TICK ((pc_clock_t)(1000u * (F_CPU / 1000000UL)))
/* In the simulator ticks are exact: each one within 32 cycles. */
#define PC_EXACT_TICKS 1
#define PC_TICK_TOLERANCE 32u
#define PC_HAS_INTERRUPTS 1

static void pc_console_init(void)
{
    TCCR1A = 0u;
    TCCR1B = _BV(CS10);
    UCSR0A = _BV(U2X0); /* 115200 8N1 */
    UCSR0C = (uint8_t)(_BV(UCSZ01) | _BV(UCSZ00));
    UBRR0H = 0u;
    UBRR0L = 16u;
    UCSR0B = _BV(TXEN0);
}

static void pc_out_str(const char *s)
{
    while (*s != '\0') {
        while ((UCSR0A & _BV(UDRE0)) == 0u) {
        }
        UDR0 = (uint8_t)*s++;
    }
}

static void pc_out_flush(void)
{
    while ((UCSR0A & _BV(TXC0)) == 0u && (UCSR0B & _BV(TXEN0)) != 0u) {
    }
}

static pc_clock_t pc_clock_now(void)
{
    uint8_t sreg = SREG;
    pc_clock_t t;
    cli();
    t = TCNT1;
    SREG = sreg;
    return t;
}

static int pc_irq_enabled(void)
{
    return (SREG & _BV(SREG_I)) != 0u;
}

#endif /* PORT_CONTRACT_HOOKS_H */
