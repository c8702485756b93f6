/* EasyLab AVR board: interrupt-driven UART rings (avr_internal.h).
 *
 * Every USART of the part is supported; the rings and interrupt handlers
 * of those the model uses are compiled in (el_avr_config.h:
 * EL_AVR_UARTn_RX / EL_AVR_UARTn_TX, 2 to 255 bytes). The receive
 * interrupt stores bytes (and, on Modbus RTU's UART, the fine clock of the
 * last one, for its t3.5 silence); the data-register-empty interrupt sends
 * from the transmit ring and switches itself off when the ring is empty.
 *
 * Register layout: every USART of the ATmega328P and ATmega2560 has
 * UCSRnA, UCSRnB, UCSRnC, (reserved), UBRRnL, UBRRnH, UDRn at consecutive
 * addresses, so one base address describes it.
 */
#include "avr_internal.h"

#include <util/atomic.h>

#define REG_A 0u
#define REG_B 1u
#define REG_C 2u
#define REG_BRRL 4u
#define REG_BRRH 5u
#define REG_DR 6u

/* Bit positions are the same in every USART of these parts. */
#define RX_ERRORS (_BV(FE0) | _BV(DOR0) | _BV(UPE0))

typedef struct {
    volatile uint8_t *base;
    uint8_t *rx;
    uint8_t *tx;
    uint8_t rx_size;
    uint8_t tx_size;
    volatile uint8_t rx_head, rx_tail; /* head: the ISR writes; tail: we read */
    volatile uint8_t tx_head, tx_tail; /* head: we write; tail: the ISR sends */
    volatile uint32_t last_rx;
    volatile uint16_t errors;
} uart_t;

#define UART_DEFINE(n, reg)                                                                     \
    static uint8_t uart##n##_rx[EL_AVR_UART##n##_RX];                                          \
    static uint8_t uart##n##_tx[EL_AVR_UART##n##_TX];                                          \
    static uart_t uart##n = {(volatile uint8_t *)&(reg), uart##n##_rx, uart##n##_tx,            \
                             (uint8_t)(EL_AVR_UART##n##_RX), (uint8_t)(EL_AVR_UART##n##_TX),         \
                             0u, 0u, 0u, 0u, 0u, 0u};

/* The index after i in a ring of `size`. */
#define NEXT(i, size) ((uint8_t)((uint8_t)((i) + 1u) == (size) ? 0u : (uint8_t)((i) + 1u)))

/* Only Modbus RTU needs the time of the last byte (its t3.5 silence):
 * the other UARTs' interrupts do not read the clock, which makes them
 * smaller and shorter. */
#if defined(EL_AVR_MODBUS_UART)
#define STAMPS(n) (EL_AVR_MODBUS_UART == (n))
#else
#define STAMPS(n) 0
#endif

__attribute__((always_inline)) static inline void rx_isr(uart_t *u, bool stamp)
{
    uint8_t status = u->base[REG_A];
    uint8_t c = u->base[REG_DR];
    uint8_t next;
    if (stamp) {
        u->last_rx = el_avr_clock();
    }
    next = NEXT(u->rx_head, u->rx_size);
    if ((status & RX_ERRORS) != 0u || next == u->rx_tail) {
        if (u->errors != 0xFFFFu) {
            u->errors++;
        }
        return;
    }
    u->rx[u->rx_head] = c;
    u->rx_head = next;
}

__attribute__((always_inline)) static inline void udre_isr(uart_t *u)
{
    uint8_t tail = u->tx_tail;
    if (tail != u->tx_head) {
        u->base[REG_DR] = u->tx[tail];
        tail = NEXT(tail, u->tx_size);
        u->tx_tail = tail;
    }
    if (tail == u->tx_head) {
        u->base[REG_B] &= (uint8_t)~_BV(UDRIE0);
    }
}

#if defined(EL_AVR_UART0_RX)
UART_DEFINE(0, UCSR0A)
#define UART0_PTR (&uart0)
#if defined(USART0_RX_vect)
ISR(USART0_RX_vect) { rx_isr(&uart0, STAMPS(0)); }
ISR(USART0_UDRE_vect) { udre_isr(&uart0); }
#else
ISR(USART_RX_vect) { rx_isr(&uart0, STAMPS(0)); }
ISR(USART_UDRE_vect) { udre_isr(&uart0); }
#endif
#else
#define UART0_PTR ((uart_t *)0)
#endif

#if defined(EL_AVR_UART1_RX)
UART_DEFINE(1, UCSR1A)
#define UART1_PTR (&uart1)
ISR(USART1_RX_vect) { rx_isr(&uart1, STAMPS(1)); }
ISR(USART1_UDRE_vect) { udre_isr(&uart1); }
#else
#define UART1_PTR ((uart_t *)0)
#endif

#if defined(EL_AVR_UART2_RX)
UART_DEFINE(2, UCSR2A)
#define UART2_PTR (&uart2)
ISR(USART2_RX_vect) { rx_isr(&uart2, STAMPS(2)); }
ISR(USART2_UDRE_vect) { udre_isr(&uart2); }
#else
#define UART2_PTR ((uart_t *)0)
#endif

#if defined(EL_AVR_UART3_RX)
UART_DEFINE(3, UCSR3A)
#define UART3_PTR (&uart3)
ISR(USART3_RX_vect) { rx_isr(&uart3, STAMPS(3)); }
ISR(USART3_UDRE_vect) { udre_isr(&uart3); }
#else
#define UART3_PTR ((uart_t *)0)
#endif

static uart_t *uart(uint8_t n)
{
    switch (n) {
    case 0u: return UART0_PTR;
    case 1u: return UART1_PTR;
    case 2u: return UART2_PTR;
    case 3u: return UART3_PTR;
    default: return (uart_t *)0;
    }
}

void el_avr_uart_open(uint8_t n, uint32_t baud, uint8_t parity)
{
    uart_t *u = uart(n);
    uint16_t ubrr;
    uint8_t c = (uint8_t)(_BV(UCSZ01) | _BV(UCSZ00)); /* 8 data bits, 1 stop bit */
    if (u == (uart_t *)0 || baud == 0u) {
        return;
    }
    if (parity == EL_AVR_PARITY_EVEN) {
        c |= _BV(UPM01);
    } else if (parity == EL_AVR_PARITY_ODD) {
        c |= (uint8_t)(_BV(UPM01) | _BV(UPM00));
    }
    /* Double speed; the nearest divisor. */
    ubrr = (uint16_t)((F_CPU + 4u * baud) / (8u * baud) - 1u);
    ATOMIC_BLOCK(ATOMIC_RESTORESTATE) {
        u->base[REG_B] = 0u;
        u->rx_head = u->rx_tail = 0u;
        u->tx_head = u->tx_tail = 0u;
        u->errors = 0u;
        /* simavr computes the bit time when UBRRnL is written: U2X and
         * the frame format first, UBRRnL last. */
        u->base[REG_A] = _BV(U2X0);
        u->base[REG_C] = c;
        u->base[REG_BRRH] = (uint8_t)(ubrr >> 8);
        u->base[REG_BRRL] = (uint8_t)ubrr;
        u->base[REG_B] = (uint8_t)(_BV(RXCIE0) | _BV(RXEN0) | _BV(TXEN0));
    }
}

int16_t el_avr_uart_getc(uint8_t n)
{
    uart_t *u = uart(n);
    uint8_t tail, c;
    if (u == (uart_t *)0) {
        return -1;
    }
    tail = u->rx_tail;
    if (tail == u->rx_head) {
        return -1;
    }
    c = u->rx[tail];
    u->rx_tail = NEXT(tail, u->rx_size);
    return (int16_t)c;
}

uint8_t el_avr_uart_available(uint8_t n)
{
    uart_t *u = uart(n);
    if (u == (uart_t *)0) {
        return 0u;
    }
    {
        uint8_t head = u->rx_head, tail = u->rx_tail;
        return (uint8_t)(head >= tail ? head - tail : u->rx_size - tail + head);
    }
}

uint16_t el_avr_uart_read(uint8_t n, uint8_t *buf, uint16_t max)
{
    uint16_t got = 0u;
    int16_t c;
    while (got < max && (c = el_avr_uart_getc(n)) >= 0) {
        buf[got++] = (uint8_t)c;
    }
    return got;
}

bool el_avr_uart_write(uint8_t n, const uint8_t *data, uint16_t len, uint16_t wait_ms)
{
    uart_t *u = uart(n);
    uint32_t start, span;
    uint8_t head;
    uint16_t i;
    if (u == (uart_t *)0 || len >= u->tx_size) {
        return false;
    }
    start = el_avr_clock();
    span = el_avr_clock_from_us((uint32_t)wait_ms * 1000u);
    for (;;) {
        uint8_t head = u->tx_head, tail = u->tx_tail;
        uint8_t used = (uint8_t)(head >= tail ? head - tail : u->tx_size - tail + head);
        uint8_t room = (uint8_t)(u->tx_size - 1u - used);
        if (room >= len) {
            break;
        }
        /* Waiting only helps while the interrupt drains the ring. */
        if ((SREG & _BV(SREG_I)) == 0u || el_avr_clock() - start >= span) {
            return false;
        }
    }
    head = u->tx_head;
    for (i = 0u; i < len; i++) {
        u->tx[head] = data[i];
        head = NEXT(head, u->tx_size);
    }
    u->tx_head = head;
    ATOMIC_BLOCK(ATOMIC_RESTORESTATE) {
        u->base[REG_B] |= _BV(UDRIE0);
    }
    return true;
}

uint32_t el_avr_uart_last_rx(uint8_t n)
{
    uart_t *u = uart(n);
    uint32_t t = 0u;
    if (u != (uart_t *)0) {
        ATOMIC_BLOCK(ATOMIC_RESTORESTATE) {
            t = u->last_rx;
        }
    }
    return t;
}

uint16_t el_avr_uart_errors(uint8_t n)
{
    uart_t *u = uart(n);
    uint16_t e = 0u;
    if (u != (uart_t *)0) {
        ATOMIC_BLOCK(ATOMIC_RESTORESTATE) {
            e = u->errors;
        }
    }
    return e;
}
