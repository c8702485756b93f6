/* EasyLab AVR board: interrupt-driven UART rings (avr_internal.h).
 *
 * Every USART of the part is supported; the rings and interrupt handlers
 * of those the model uses are compiled in (el_avr_config.h:
 * EL_AVR_UARTn_RX / EL_AVR_UARTn_TX, 2 to 255 bytes). The receive
 * interrupt stores bytes (and, on Modbus RTU's UART, the fine clock of the
 * last one, for its t3.5 silence); the data-register-empty interrupt sends
 * from the transmit ring and switches itself off when the ring is empty.
 *
 * A UART whose EL_AVR_UARTn_TX is 0 has no transmit ring: a write sends
 * straight from the caller's bytes, and while they go out a read takes
 * nothing. Only the debug UART is one (el_avr_config.h): the debug server writes its
 * response buffer only on a request's delimiter it read (el_debug.h), so
 * the response being sent stays as it is. One pointer and count serve.
 *
 * Each function is expanded once per UART in use with that UART's
 * registers, rings and ring sizes as constants (`UART(n)`, a compound
 * literal the compiler folds): every access is a direct load or store,
 * with no descriptor in RAM and no pointer walk. On the ATmega328P (one
 * USART) that is one copy; a model on several USARTs of the ATmega2560
 * gets one copy per USART.
 *
 * Register layout: every USART of the ATmega328P and ATmega2560 has
 * UCSRnA, UCSRnB, UCSRnC, (reserved), UBRRnL, UBRRnH, UDRn at consecutive
 * addresses, so one base address describes it.
 */
#include "avr_internal.h"

#include <util/atomic.h>
#include <util/delay.h>

#define REG_A 0u
#define REG_B 1u
#define REG_C 2u
#define REG_BRRL 4u
#define REG_BRRH 5u
#define REG_DR 6u

/* Bit positions are the same in every USART of these parts. */
#define RX_ERRORS (_BV(FE0) | _BV(DOR0) | _BV(UPE0))

/* A UART's indices (and the Modbus UART's time stamp): the only RAM
 * besides the rings. */
typedef struct {
    volatile uint8_t rx_head, rx_tail; /* head: the ISR writes; tail: we read */
} uart_rx_state_t;
typedef struct {
    volatile uint8_t tx_head, tx_tail; /* head: we write; tail: the ISR sends */
} uart_tx_state_t;

/* A UART as constants: its registers, state, rings and ring sizes. */
typedef struct {
    volatile uint8_t *base;
    uart_rx_state_t *r;
    uart_tx_state_t *t;
    uint8_t *rx;
    uint8_t *tx;
    uint8_t rx_size;
    uint8_t tx_size;
    uint8_t n;
} uart_t;

/* A UART without a transmit ring keeps its transmit indices and a 1-byte
 * ring (ISO C has no empty arrays) that no code reaches: the linker drops
 * them. */
#define UART_DEFINE(n)                                                              \
    static uint8_t uart##n##_rx[EL_AVR_UART##n##_RX];                               \
    static uint8_t uart##n##_tx[EL_AVR_UART##n##_TX + (EL_AVR_UART##n##_TX == 0u)]; \
    static uart_rx_state_t uart##n##_rx_state;                                      \
    static uart_tx_state_t uart##n##_tx_state;

#define UART(n)                                                                                 \
    ((uart_t){(volatile uint8_t *)&(UCSR##n##A), &uart##n##_rx_state, &uart##n##_tx_state,       \
              uart##n##_rx, uart##n##_tx, (uint8_t)(EL_AVR_UART##n##_RX), (uint8_t)(EL_AVR_UART##n##_TX), \
              (uint8_t)(n)})

/* The index after i in a ring of `size`. */
#define NEXT(i, size) ((uint8_t)((uint8_t)((i) + 1u) == (size) ? 0u : (uint8_t)((i) + 1u)))

#define INLINE __attribute__((always_inline)) static inline

/* Only Modbus RTU needs the time of the last byte (its t3.5 silence): the
 * other UARTs' interrupts do not read the clock, which makes them smaller
 * and shorter. */
#if defined(EL_AVR_MODBUS_UART)
static volatile uint32_t modbus_last_rx;
#define STAMPS(u) (EL_AVR_MODBUS_UART == (u).n)
#else
#define STAMPS(u) 0
#endif

/* The UART without a transmit ring (at most one: the #error below) sends
 * from `direct_next`, `direct_left` bytes left; its interrupt is on only
 * while some are. */
#define DIRECT(u) ((u).tx_size == 0u)
#if (defined(EL_AVR_UART0_TX) && EL_AVR_UART0_TX == 0) + (defined(EL_AVR_UART1_TX) && EL_AVR_UART1_TX == 0) \
    + (defined(EL_AVR_UART2_TX) && EL_AVR_UART2_TX == 0) + (defined(EL_AVR_UART3_TX) && EL_AVR_UART3_TX == 0) > 1
#error "el_avr_config.h: one UART at most without a transmit ring (EL_AVR_UARTn_TX 0)"
#endif
static const uint8_t *volatile direct_next;
static volatile uint8_t direct_left;

/* A byte received with a framing, parity or overrun error, or with no room
 * in the ring, is dropped: the protocols on top check their frames. */
INLINE void rx_isr(uart_t u)
{
    uint8_t status = u.base[REG_A];
    uint8_t c = u.base[REG_DR];
    uint8_t head = u.r->rx_head;
    uint8_t next = NEXT(head, u.rx_size);
#if defined(EL_AVR_MODBUS_UART)
    if (STAMPS(u)) {
        modbus_last_rx = el_avr_clock();
    }
#endif
    if ((status & RX_ERRORS) == 0u && next != u.r->rx_tail) {
        u.rx[head] = c;
        u.r->rx_head = next;
    }
}

INLINE void udre_isr(uart_t u)
{
    uint8_t tail;
    if (DIRECT(u)) {
        const uint8_t *next = direct_next;
        u.base[REG_DR] = *next++;
        direct_next = next;
        if (--direct_left == 0u) {
            u.base[REG_B] &= (uint8_t)~_BV(UDRIE0);
        }
        return;
    }
    tail = u.t->tx_tail;
    if (tail != u.t->tx_head) {
        u.base[REG_DR] = u.tx[tail];
        tail = NEXT(tail, u.tx_size);
        u.t->tx_tail = tail;
    }
    if (tail == u.t->tx_head) {
        u.base[REG_B] &= (uint8_t)~_BV(UDRIE0);
    }
}

INLINE void open_of(uart_t u, uint16_t ubrr, uint8_t frame)
{
    ATOMIC_BLOCK(ATOMIC_RESTORESTATE) {
        u.base[REG_B] = 0u;
        u.r->rx_head = u.r->rx_tail = 0u;
        if (DIRECT(u)) {
            direct_left = 0u;
        } else {
            u.t->tx_head = u.t->tx_tail = 0u;
        }
        /* simavr computes the bit time when UBRRnL is written: U2X and
         * the frame format first, UBRRnL last. */
        u.base[REG_A] = _BV(U2X0);
        u.base[REG_C] = frame;
        u.base[REG_BRRH] = (uint8_t)(ubrr >> 8);
        u.base[REG_BRRL] = (uint8_t)ubrr;
        u.base[REG_B] = (uint8_t)(_BV(RXCIE0) | _BV(RXEN0) | _BV(TXEN0));
    }
}

INLINE int16_t getc_of(uart_t u)
{
    uint8_t tail = u.r->rx_tail, c;
    if (tail == u.r->rx_head) {
        return -1;
    }
    c = u.rx[tail];
    u.r->rx_tail = NEXT(tail, u.rx_size);
    return (int16_t)c;
}

INLINE uint8_t available_of(uart_t u)
{
    uint8_t head = u.r->rx_head, tail = u.r->rx_tail;
    return (uint8_t)(head >= tail ? head - tail : u.rx_size - tail + head);
}

INLINE uint16_t read_of(uart_t u, uint8_t *buf, uint16_t max)
{
    uint16_t got = 0u;
    int16_t c;
    if (DIRECT(u) && direct_left != 0u) {
        return 0u;
    }
    while (got < max && (c = getc_of(u)) >= 0) {
        buf[got++] = (uint8_t)c;
    }
    return got;
}

/* Free bytes in the transmit ring (one slot stays empty). */
INLINE uint8_t tx_room(uart_t u)
{
    uint8_t head = u.t->tx_head, tail = u.t->tx_tail;
    uint8_t used = (uint8_t)(head >= tail ? head - tail : u.tx_size - tail + head);
    return (uint8_t)(u.tx_size - 1u - used);
}

INLINE bool write_of(uart_t u, const uint8_t *data, uint16_t len, uint16_t wait_ms)
{
    uint8_t head, polls = 10u;
    uint16_t i;
    if (DIRECT(u)) {
        /* Never waits: the caller's bytes must not change before they are
         * out, so a caller writes only once the last write is done. */
        if (len == 0u || len > UINT8_MAX || direct_left != 0u) {
            return false;
        }
        direct_next = data;
        direct_left = (uint8_t)len;
        /* Not atomic, and need not be: with nothing left to send the
         * interrupt is off, the only other writer of UCSRnB. */
        u.base[REG_B] |= _BV(UDRIE0);
        return true;
    }
    if (len >= u.tx_size) {
        return false;
    }
    /* Wait for room, checking every 100 us of CPU time (interrupts make
     * the wait longer, never shorter); no clock to read. Waiting only
     * helps while the interrupt drains the ring. */
    while (tx_room(u) < len) {
        if ((SREG & _BV(SREG_I)) == 0u) {
            return false;
        }
        _delay_us(100);
        if (--polls == 0u) {
            if (wait_ms == 0u) {
                return false;
            }
            wait_ms--;
            polls = 10u;
        }
    }
    head = u.t->tx_head;
    for (i = 0u; i < len; i++) {
        u.tx[head] = data[i];
        head = NEXT(head, u.tx_size);
    }
    u.t->tx_head = head;
    ATOMIC_BLOCK(ATOMIC_RESTORESTATE) {
        u.base[REG_B] |= _BV(UDRIE0);
    }
    return true;
}

/* ---- the UARTs in use: state, interrupts, one case of each function ---- */

#if defined(EL_AVR_UART0_RX)
UART_DEFINE(0)
#if defined(USART0_RX_vect)
ISR(USART0_RX_vect) { rx_isr(UART(0)); }
ISR(USART0_UDRE_vect) { udre_isr(UART(0)); }
#else
ISR(USART_RX_vect) { rx_isr(UART(0)); }
ISR(USART_UDRE_vect) { udre_isr(UART(0)); }
#endif
#define CASE0(what, ...) case 0u: return what(UART(0), ##__VA_ARGS__);
#else
#define CASE0(what, ...)
#endif

#if defined(EL_AVR_UART1_RX)
UART_DEFINE(1)
ISR(USART1_RX_vect) { rx_isr(UART(1)); }
ISR(USART1_UDRE_vect) { udre_isr(UART(1)); }
#define CASE1(what, ...) case 1u: return what(UART(1), ##__VA_ARGS__);
#else
#define CASE1(what, ...)
#endif

#if defined(EL_AVR_UART2_RX)
UART_DEFINE(2)
ISR(USART2_RX_vect) { rx_isr(UART(2)); }
ISR(USART2_UDRE_vect) { udre_isr(UART(2)); }
#define CASE2(what, ...) case 2u: return what(UART(2), ##__VA_ARGS__);
#else
#define CASE2(what, ...)
#endif

#if defined(EL_AVR_UART3_RX)
UART_DEFINE(3)
ISR(USART3_RX_vect) { rx_isr(UART(3)); }
ISR(USART3_UDRE_vect) { udre_isr(UART(3)); }
#define CASE3(what, ...) case 3u: return what(UART(3), ##__VA_ARGS__);
#else
#define CASE3(what, ...)
#endif

/* `what(UART(n), ...)` for the UART numbered n; `none` for a UART not in use. */
#define ON_UART(n, none, what, ...)                                                  \
    switch (n) {                                                                     \
    CASE0(what, ##__VA_ARGS__) CASE1(what, ##__VA_ARGS__) CASE2(what, ##__VA_ARGS__) \
    CASE3(what, ##__VA_ARGS__)                                                       \
    default: return none;                                                            \
    }

#if defined(EL_AVR_UART0_RX) || defined(EL_AVR_UART1_RX) || defined(EL_AVR_UART2_RX) || defined(EL_AVR_UART3_RX)

/* open_of returns nothing: a wrapper that does, for ON_UART. */
INLINE bool open_ok(uart_t u, uint16_t ubrr, uint8_t frame)
{
    open_of(u, ubrr, frame);
    return true;
}

bool el_avr_uart_setup(uint8_t n, uint16_t ubrr, uint8_t frame)
{
    ON_UART(n, false, open_ok, ubrr, frame)
}

int16_t el_avr_uart_getc(uint8_t n)
{
    ON_UART(n, -1, getc_of)
}

uint8_t el_avr_uart_available(uint8_t n)
{
    ON_UART(n, 0u, available_of)
}

uint16_t el_avr_uart_read(uint8_t n, uint8_t *buf, uint16_t max)
{
    ON_UART(n, 0u, read_of, buf, max)
}

bool el_avr_uart_write(uint8_t n, const uint8_t *data, uint16_t len, uint16_t wait_ms)
{
    ON_UART(n, false, write_of, data, len, wait_ms)
}

#if defined(EL_AVR_MODBUS_UART)
uint32_t el_avr_uart_last_rx(void)
{
    uint32_t t;
    ATOMIC_BLOCK(ATOMIC_RESTORESTATE) {
        t = modbus_last_rx;
    }
    return t;
}
#endif

#else
typedef int el_avr_no_uart_t; /* no UART in use (ISO C: a translation unit declares something) */
#endif
