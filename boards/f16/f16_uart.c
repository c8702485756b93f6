/* EasyLab f16 board: UART1 of the MB90F543 (mb90f543_regs.h, chapter
 * "UART1") with interrupt-driven rings, and the transports of the debug and
 * service interfaces on it.
 *
 * The dedicated baud rate generator divides the machine clock by
 * EL_F16_UART1_DIV (U1CDCR) and by 208 << EL_F16_UART1_CS (SMR1's CS): the
 * backend picks the pair nearest to the model's baud rate and refuses one
 * that is more than 2 % off. 8 data bits, 1 stop bit, the model's parity.
 *
 * Debug (runtime_c/el_debug.h): a frame waits up to EL_F16_DEBUG_TX_WAIT_MS
 * for room in the transmit ring, else it is dropped (the server counts it).
 * RESET is refused: nothing here restarts the part.
 *
 * A remote-execution proxy's link (runtime_c/el_remote.h, a proxy build
 * only): 8N1 at EL_REMOTE_BAUD; a frame waits for room in the transmit
 * ring as long as a full ring takes to send, else it is dropped; STOP
 * restarts the part once its answer has left (el_f16_hw_reset).
 *
 * Modbus RTU (runtime_c/el_modbus_port.h): the end of a request is a
 * silence of 3.5 characters (1750 us above 19200 baud) after the last byte,
 * measured on the port's fine clock from the receive interrupt's time stamp.
 */
#include "f16_internal.h"
#include "f16_compiler.h"
#include "mb90f543_regs.h"

#if defined(EL_F16_UART1_RX)

#if defined(EL_DEBUG) && EL_DEBUG && !(defined(EL_RELEASE) && EL_RELEASE)
#include "el_debug.h"
#endif

#ifndef EL_F16_DEBUG_TX_WAIT_MS
#define EL_F16_DEBUG_TX_WAIT_MS 50u
#endif

static uint8_t rx_ring[EL_F16_UART1_RX];
static uint8_t tx_ring[EL_F16_UART1_TX];
static volatile uint16_t rx_head, rx_tail, tx_head, tx_tail; /* head: next write */
static volatile uint32_t rx_stamp;                            /* fine clock at the last byte */

static uint16_t ring_next(uint16_t i, uint16_t size)
{
    return (uint16_t)(i + 1u == size ? 0u : i + 1u);
}

EL_F16_ISR(el_f16_uart1_rx_interrupt)
{
    uint8_t status = EL_F16_SSR1;
    uint8_t c = EL_F16_SIDR1;
    if ((status & (EL_F16_SSR_ORE | EL_F16_SSR_FRE | EL_F16_SSR_PE)) != 0u) {
        EL_F16_SCR1 = (uint8_t)(EL_F16_SCR1 & (uint8_t)~EL_F16_SCR_REC); /* drop the byte, clear the errors */
        return;
    }
    if (ring_next(rx_head, EL_F16_UART1_RX) != rx_tail) {
        rx_ring[rx_head] = c;
        rx_head = ring_next(rx_head, EL_F16_UART1_RX);
    }
    rx_stamp = el_f16_clock();
}

EL_F16_ISR(el_f16_uart1_tx_interrupt)
{
    if (tx_tail == tx_head) {
        EL_F16_SSR1 = (uint8_t)(EL_F16_SSR1 & (uint8_t)~EL_F16_SSR_TIE);
        return;
    }
    EL_F16_SODR1 = tx_ring[tx_tail];
    tx_tail = ring_next(tx_tail, EL_F16_UART1_TX);
}

static void uart1_open(uint8_t scr_parity)
{
    rx_head = rx_tail = tx_head = tx_tail = 0u;
    EL_F16_ICR(EL_F16_ICR_OF_VECTOR(EL_F16_UART1_RX_VECTOR)) = EL_F16_UART_LEVEL;
    EL_F16_ICR(EL_F16_ICR_OF_VECTOR(EL_F16_UART1_TX_VECTOR)) = EL_F16_UART_LEVEL;
    EL_F16_U1CDCR = (uint8_t)(EL_F16_CDCR_MD | (uint8_t)(EL_F16_UART1_DIV - 1u));
    EL_F16_SMR1 = (uint8_t)(((uint8_t)EL_F16_UART1_CS << EL_F16_SMR_CS_SHIFT) | EL_F16_SMR_MD_ASYNC | EL_F16_SMR_SOE);
    EL_F16_SCR1 = (uint8_t)(scr_parity | EL_F16_SCR_CL8 | EL_F16_SCR_REC | EL_F16_SCR_RXE | EL_F16_SCR_TXE);
    EL_F16_SSR1 = EL_F16_SSR_RIE;
}

static int16_t uart1_getc(void)
{
    el_irq_state_t state = el_f16_hw_irq_save();
    int16_t c = -1;
    if (rx_tail != rx_head) {
        c = rx_ring[rx_tail];
        rx_tail = ring_next(rx_tail, EL_F16_UART1_RX);
    }
    el_f16_hw_irq_restore(state);
    return c;
}

#if (defined(EL_F16_DEBUG_UART) && defined(EL_DEBUG_SERVER) && EL_DEBUG_SERVER) || \
    (defined(EL_F16_REMOTE_UART) && defined(EL_REMOTE_PROXY) && EL_REMOTE_PROXY)
/* What the ring holds, up to `max` bytes (the debug server's and the proxy's link). */
static uint16_t uart1_read(uint8_t *buf, uint16_t max)
{
    uint16_t n = 0u;
    while (n < max) {
        int16_t c = uart1_getc();
        if (c < 0) {
            break;
        }
        buf[n++] = (uint8_t)c;
    }
    return n;
}
#endif

/* Queue `len` bytes whole, waiting up to `wait_ms` for room; false: none queued. */
static bool uart1_write(const uint8_t *data, uint16_t len, uint16_t wait_ms)
{
    uint32_t start = el_f16_clock();
    uint32_t span = el_f16_clock_from_us((uint32_t)wait_ms * 1000u);
    uint16_t i;
    for (;;) {
        el_irq_state_t state = el_f16_hw_irq_save();
        uint16_t used = tx_head >= tx_tail ? (uint16_t)(tx_head - tx_tail)
                                           : (uint16_t)(EL_F16_UART1_TX - tx_tail + tx_head);
        if ((uint16_t)(EL_F16_UART1_TX - 1u - used) >= len) {
            for (i = 0u; i < len; i++) {
                tx_ring[tx_head] = data[i];
                tx_head = ring_next(tx_head, EL_F16_UART1_TX);
            }
            EL_F16_SSR1 = (uint8_t)(EL_F16_SSR1 | EL_F16_SSR_TIE); /* TDRE is set: the interrupt comes */
            el_f16_hw_irq_restore(state);
            return true;
        }
        el_f16_hw_irq_restore(state);
        if (el_f16_clock() - start >= span) {
            return false;
        }
    }
}

#if defined(EL_F16_DEBUG_UART) && defined(EL_DEBUG_SERVER) && EL_DEBUG_SERVER

void el_f16_debug_open(void)
{
    uart1_open(0u); /* no parity */
}

uint16_t el_debug_port_read(uint8_t *buf, uint16_t max)
{
    return uart1_read(buf, max);
}

bool el_debug_port_write(const uint8_t *frame, uint16_t len)
{
    return uart1_write(frame, len, EL_F16_DEBUG_TX_WAIT_MS);
}

bool el_debug_port_reset(uint8_t flags)
{
    (void)flags;
    return false;
}

#endif

#if defined(EL_F16_REMOTE_UART) && defined(EL_REMOTE_PROXY) && EL_REMOTE_PROXY
#include "el_remote.h"

/* Milliseconds to send a full transmit ring (10 bits a byte), rounded up. */
#define REMOTE_TX_WAIT_MS ((uint16_t)((uint32_t)EL_F16_UART1_TX * 10000UL / (uint32_t)EL_REMOTE_BAUD + 2UL))

void el_f16_remote_open(void)
{
    uart1_open(0u); /* 8N1 */
}

uint16_t el_remote_port_read(uint8_t *buf, uint16_t max)
{
    return uart1_read(buf, max);
}

bool el_remote_port_write(const uint8_t *frame, uint16_t len)
{
    return uart1_write(frame, len, REMOTE_TX_WAIT_MS);
}

bool el_remote_port_stopping(void)
{
    return false; /* an MCU runs until reset */
}

void el_remote_port_end(void)
{
    /* STOP's answer drains from the ring (interrupts stay on), then a
     * software reset restarts the part: its boot drives the actuators to
     * their safe values and waits for the next host's START, at tick 0. */
    uint32_t start = el_f16_clock();
    while (el_f16_clock() - start < el_f16_clock_from_us((uint32_t)REMOTE_TX_WAIT_MS * 1000u)) {
    }
    el_f16_hw_reset();
}

#endif

#if defined(EL_F16_MODBUS_UART)
#include "el_modbus_port.h"

static uint32_t mb_t35;  /* fine-clock units of a t3.5 silence */
static bool mb_in_frame; /* bytes were taken since the last silence */

uint8_t el_port_mb_rtu_open(uint8_t uart, uint32_t baud, uint8_t parity, uint8_t unit)
{
    (void)unit;
    if (uart != EL_F16_MODBUS_UART || baud == 0u) {
        return EL_MB_PORT_OFF;
    }
    uart1_open(parity == EL_MB_PARITY_EVEN ? (uint8_t)(EL_F16_SCR_PEN | EL_F16_SCR_P_EVEN)
               : parity == EL_MB_PARITY_ODD ? (uint8_t)(EL_F16_SCR_PEN | EL_F16_SCR_P_ODD)
                                            : (uint8_t)0u);
    /* 3.5 characters of 11 bits; 1750 us above 19200 baud. */
    mb_t35 = el_f16_clock_from_us(baud > 19200u ? 1750u : (38500000u + baud - 1u) / baud);
    mb_in_frame = false;
    return EL_MB_PORT_TIMED;
}

int16_t el_port_mb_rtu_getc(void)
{
    int16_t c = uart1_getc();
    el_irq_state_t state;
    uint32_t last;
    bool empty;
    if (c >= 0) {
        mb_in_frame = true;
        return c;
    }
    if (!mb_in_frame) {
        return EL_MB_NONE;
    }
    state = el_f16_hw_irq_save();
    last = rx_stamp;
    empty = rx_tail == rx_head;
    el_f16_hw_irq_restore(state);
    if (empty && el_f16_clock() - last >= mb_t35) {
        mb_in_frame = false; /* the silence after the last byte ends the frame */
        return EL_MB_SILENCE;
    }
    return EL_MB_NONE;
}

void el_port_mb_rtu_send(const uint8_t *adu, uint16_t len)
{
    /* The ring holds a whole ADU (project.py): the reply goes whole, once
     * the last one has left. */
    while (!uart1_write(adu, len, 200u)) {
    }
}

#endif

#else
/* No UART in this model (ISO C wants a declaration in every file). */
typedef int el_f16_uart_unused_t;
#endif
