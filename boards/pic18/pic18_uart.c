/* EasyLab PIC18 board: the EUSART (RX on RC7, TX on RC6) with
 * interrupt-driven rings (pic18_hw.h).
 *
 * The rings exist when the model uses the UART (el_pic18_config.h:
 * EL_PIC18_UART_RX / EL_PIC18_UART_TX, 2 to 255 bytes). The receive
 * interrupt stores bytes and the fine clock of the last one (Modbus'
 * t3.5 silence); the transmit interrupt sends from the ring and switches
 * itself off when the ring is empty. With EL_PIC18_UART_TX 0 (the debug
 * interface's UART) there is no transmit ring: a write sends straight
 * from the caller's bytes, which the debug server leaves alone until it
 * reads again (el_debug.h), and a read takes nothing while they go out. The baud rate generator runs in
 * 16-bit mode with BRGH: baud = Fcy / (SPBRG + 1) (115200 baud: 86,
 * -0.2 %). Parity is the 9th bit, computed and checked here.
 */
#include "el_pic18.h"
#include "pic18_hw.h"

/* Polled output, for programs without the ring (port_contract.c): 115200 8N1. */
void el_pic18_uart_putc_polled(uint8_t c)
{
    if (!RCSTAbits.SPEN) {
        TRISCbits.TRISC6 = 1;
        TRISCbits.TRISC7 = 1;
        BAUDCON = 0x08u; /* BRG16 */
        TXSTA = 0x24u;   /* TXEN, BRGH */
        SPBRGH = 0u;
        SPBRG = (uint8_t)(EL_PIC18_FCY / 115200UL - 1u);
        RCSTA = 0x80u;   /* SPEN */
    }
    while (!PIR1bits.TXIF) {
    }
    TXREG = c;
}

void el_pic18_uart_flush_polled(void)
{
    while (RCSTAbits.SPEN && !TXSTAbits.TRMT) {
    }
}

#if defined(EL_PIC18_UART_RX)

static uint8_t rx[EL_PIC18_UART_RX];
static volatile uint8_t rx_head, rx_tail; /* head: the interrupt writes; tail: we read */
#define DIRECT (EL_PIC18_UART_TX == 0)
#if DIRECT
static const uint8_t *volatile direct_next; /* the caller's bytes going out */
static volatile uint8_t direct_left;
#else
static uint8_t tx[EL_PIC18_UART_TX];
static volatile uint8_t tx_head, tx_tail; /* head: we write; tail: the interrupt sends */
#endif
static volatile uint32_t last_rx;
static volatile uint16_t errors;
static uint8_t parity_mode;

#define NEXT(i, size) ((uint8_t)((uint8_t)((i) + 1u) == (uint8_t)(size) ? 0u : (uint8_t)((i) + 1u)))

/* 1 when the byte has an odd number of ones. */
static uint8_t odd_ones(uint8_t v)
{
    v ^= (uint8_t)(v >> 4);
    v ^= (uint8_t)(v >> 2);
    v ^= (uint8_t)(v >> 1);
    return (uint8_t)(v & 1u);
}

/* The 9th bit that gives the byte its parity. */
static uint8_t parity_bit(uint8_t v)
{
    return (uint8_t)(odd_ones(v) ^ (parity_mode == EL_PIC18_PARITY_ODD ? 1u : 0u));
}

static void count_error(void)
{
    if (errors != 0xFFFFu) {
        errors++;
    }
}

/* One byte to the transmitter, its parity in the 9th bit. */
static void send(uint8_t c)
{
    if (parity_mode != EL_PIC18_PARITY_NONE) {
        TXSTAbits.TX9D = parity_bit(c);
    }
    TXREG = c;
}

/* From the interrupt handler (pic18_hw.c). */
void el_pic18_uart_isr(void)
{
    while (PIR1bits.RCIF) {
        uint8_t status = RCSTA;
        uint8_t c = RCREG;
        uint8_t next = NEXT(rx_head, EL_PIC18_UART_RX);
        if ((status & 0x02u) != 0u) { /* OERR: only clearing CREN clears it */
            RCSTAbits.CREN = 0;
            RCSTAbits.CREN = 1;
            count_error();
            continue;
        }
        last_rx = el_pic18_clock();
        if ((status & 0x04u) != 0u || next == rx_tail ||
            (parity_mode != EL_PIC18_PARITY_NONE && (status & 0x01u) != parity_bit(c))) {
            count_error(); /* FERR, a full ring, a parity error */
            continue;
        }
        rx[rx_head] = c;
        rx_head = next;
    }
    if (PIE1bits.TXIE && PIR1bits.TXIF) {
#if DIRECT
        if (direct_left != 0u) {
            const uint8_t *next = direct_next;
            send(*next);
            direct_next = next + 1;
            direct_left--;
        }
        if (direct_left == 0u) {
            PIE1bits.TXIE = 0;
        }
#else
        uint8_t tail = tx_tail;
        if (tail != tx_head) {
            send(tx[tail]);
            tail = NEXT(tail, EL_PIC18_UART_TX);
            tx_tail = tail;
        }
        if (tail == tx_head) {
            PIE1bits.TXIE = 0;
        }
#endif
    }
}

void el_pic18_uart_open(uint32_t baud, uint8_t parity)
{
    uint16_t brg;
    uint8_t state;
    if (baud == 0u) {
        return;
    }
    brg = (uint16_t)((EL_PIC18_FCY + baud / 2u) / baud - 1u);
    state = el_pic18_irq_save();
    RCSTA = 0u;
    PIE1bits.RCIE = 0;
    PIE1bits.TXIE = 0;
    rx_head = rx_tail = 0u;
#if DIRECT
    direct_left = 0u;
#else
    tx_head = tx_tail = 0u;
#endif
    errors = 0u;
    parity_mode = parity;
    TRISCbits.TRISC6 = 1; /* the EUSART drives TX itself */
    TRISCbits.TRISC7 = 1;
    BAUDCON = 0x08u;      /* BRG16 */
    SPBRGH = (uint8_t)(brg >> 8);
    SPBRG = (uint8_t)brg;
    TXSTA = (uint8_t)(0x24u | (parity != EL_PIC18_PARITY_NONE ? 0x40u : 0u)); /* TXEN, BRGH, TX9 */
    RCSTA = (uint8_t)(0x90u | (parity != EL_PIC18_PARITY_NONE ? 0x40u : 0u)); /* SPEN, CREN, RX9 */
    PIE1bits.RCIE = 1;
    el_pic18_irq_restore(state);
}

int16_t el_pic18_uart_getc(void)
{
    uint8_t tail = rx_tail, c;
    if (tail == rx_head) {
        return -1;
    }
    c = rx[tail];
    rx_tail = NEXT(tail, EL_PIC18_UART_RX);
    return (int16_t)c;
}

uint8_t el_pic18_uart_available(void)
{
    uint8_t head = rx_head, tail = rx_tail;
    return (uint8_t)(head >= tail ? head - tail : (uint8_t)(EL_PIC18_UART_RX - tail + head));
}

uint16_t el_pic18_uart_read(uint8_t *buf, uint16_t max)
{
    uint16_t got = 0u;
    int16_t c;
#if DIRECT
    if (direct_left != 0u) { /* the bytes going out are the server's: it may not answer again yet */
        return 0u;
    }
#endif
    while (got < max && (c = el_pic18_uart_getc()) >= 0) {
        buf[got++] = (uint8_t)c;
    }
    return got;
}

bool el_pic18_uart_write(const uint8_t *data, uint16_t len, uint16_t wait_ms)
{
#if DIRECT
    /* Never waits: the caller's bytes must stay as they are until they are
     * out, so it writes only once the last write is done. */
    (void)wait_ms;
    if (len == 0u || len > 255u || direct_left != 0u) {
        return false;
    }
    direct_next = data;
    direct_left = (uint8_t)len;
    PIE1bits.TXIE = 1;
    return true;
#else
    uint32_t start, span;
    uint8_t head;
    uint16_t i;
    if (len >= EL_PIC18_UART_TX) {
        return false;
    }
    start = el_pic18_clock();
    span = (uint32_t)wait_ms * (EL_PIC18_FCY / 1000u);
    for (;;) {
        uint8_t h = tx_head, t = tx_tail;
        uint8_t used = (uint8_t)(h >= t ? h - t : (uint8_t)(EL_PIC18_UART_TX - t + h));
        if ((uint8_t)(EL_PIC18_UART_TX - 1u - used) >= len) {
            break;
        }
        /* Waiting only helps while the interrupt drains the ring. */
        if (!INTCONbits.GIE || el_pic18_clock() - start >= span) {
            return false;
        }
        el_pic18_watchdog_kick();
    }
    head = tx_head;
    for (i = 0u; i < len; i++) {
        tx[head] = data[i];
        head = NEXT(head, EL_PIC18_UART_TX);
    }
    tx_head = head;
    PIE1bits.TXIE = 1;
    return true;
#endif
}

uint32_t el_pic18_uart_last_rx(void)
{
    uint32_t t;
    uint8_t state = el_pic18_irq_save();
    t = last_rx;
    el_pic18_irq_restore(state);
    return t;
}

uint16_t el_pic18_uart_errors(void)
{
    uint16_t e;
    uint8_t state = el_pic18_irq_save();
    e = errors;
    el_pic18_irq_restore(state);
    return e;
}

#endif
