/* EasyLab AVR board: the transports of the debug and service interfaces.
 *
 * Debug (runtime_c/el_debug.h): on the model's debug UART
 * (EL_AVR_DEBUG_UART, opened by el_port_init at EL_AVR_DEBUG_BAUD, 8N1),
 * which has no transmit ring: a response goes out straight from the
 * server's buffer. The server writes that buffer only when it meets a
 * request's delimiter among the bytes el_debug_port_read gave it, so the
 * read hands out nothing while a response goes out (the request waits in
 * the receive ring, which holds an encoded frame). A write can therefore find
 * the transmitter busy only when the server's promise is broken; it is
 * then refused at once (the server counts it in C_TX_DROPPED). Reset: the
 * watchdog restarts the MCU from boot once the reply is out.
 *
 * Modbus RTU (runtime_c/el_modbus_port.h): on the model's Modbus UART,
 * with the model's baud rate and parity, 8 data bits, 1 stop bit. The end
 * of a frame is a silence of 3.5 characters (1750 us above 19200 baud)
 * after the last received byte, measured on the fine clock (Timer2) from
 * the receive interrupt's time stamp: el_port_mb_rtu_getc returns
 * EL_MB_SILENCE once when it sees that the ring is empty and the silence
 * has lasted. Replies are queued whole (waiting for room as long as it
 * takes to send a ring's worth). Modbus TCP needs a network: the board
 * refuses it at build time.
 */
#include "avr_internal.h"
#include "el_port.h"

#include <avr/wdt.h>

#if defined(EL_DEBUG) && EL_DEBUG && !(defined(EL_RELEASE) && EL_RELEASE)
#include "el_debug.h"
#endif

#if defined(EL_DEBUG_SERVER) && EL_DEBUG_SERVER && defined(EL_AVR_DEBUG_UART)

/* In .noinit RAM (avr_port.c): 0x5A asks el_port_init to halt at the first instant. */
extern uint8_t el_avr_reset_halt;

uint16_t el_debug_port_read(uint8_t *buf, uint16_t max)
{
    return el_avr_uart_read(EL_AVR_DEBUG_UART, buf, max);
}

bool el_debug_port_write(const uint8_t *frame, uint16_t len)
{
    return el_avr_uart_write(EL_AVR_DEBUG_UART, frame, len, 0u);
}

bool el_debug_port_reset(uint8_t flags)
{
    /* RESET_HALT survives the reset in .noinit RAM (el_port_init reads it). */
    el_avr_reset_halt = (flags & EL_DBG_RESET_HALT) != 0u ? 0x5Au : 0u;
    /* Let the reply go out, then let the watchdog restart everything. */
    wdt_enable(WDTO_30MS);
    for (;;) {
    }
    return false;
}

#endif

#if defined(EL_AVR_MODBUS_UART)
#include "el_modbus_port.h"

static uint32_t mb_t35;       /* fine-clock periods of a t3.5 silence */
static bool mb_in_frame;      /* bytes were taken since the last silence */

uint8_t el_port_mb_rtu_open(uint8_t uart, uint32_t baud, uint8_t parity, uint8_t unit)
{
    uint8_t p = parity == EL_MB_PARITY_EVEN ? EL_AVR_PARITY_EVEN
                : (parity == EL_MB_PARITY_ODD ? EL_AVR_PARITY_ODD : EL_AVR_PARITY_NONE);
    (void)unit;
    if (uart != EL_AVR_MODBUS_UART || baud == 0u) {
        return EL_MB_PORT_OFF;
    }
    el_avr_uart_open(uart, baud, p);
    /* 3.5 characters of 11 bits; fixed 1750 us above 19200 baud. */
    mb_t35 = el_avr_clock_from_us(baud > 19200u ? 1750u : (38500000u + baud - 1u) / baud);
    mb_in_frame = false;
    return EL_MB_PORT_TIMED;
}

int16_t el_port_mb_rtu_getc(void)
{
    int16_t c = el_avr_uart_getc(EL_AVR_MODBUS_UART);
    if (c >= 0) {
        mb_in_frame = true;
        return c;
    }
    if (mb_in_frame) {
        /* The time stamp first: a byte arriving after it shows in the ring. */
        uint32_t last = el_avr_uart_last_rx();
        if (el_avr_uart_available(EL_AVR_MODBUS_UART) == 0u && el_avr_clock() - last >= mb_t35) {
            mb_in_frame = false; /* the silence after the last byte ends the frame */
            return EL_MB_SILENCE;
        }
    }
    return EL_MB_NONE;
}

void el_port_mb_rtu_send(const uint8_t *adu, uint16_t len)
{
    uint16_t done = 0u;
    while (done < len) {
        uint16_t chunk = (uint16_t)(len - done);
        if (chunk > (uint16_t)(EL_AVR_MODBUS_TX / 2u)) {
            chunk = (uint16_t)(EL_AVR_MODBUS_TX / 2u);
        }
        if (el_avr_uart_write(EL_AVR_MODBUS_UART, adu + done, chunk, 200u)) {
            done = (uint16_t)(done + chunk);
        } else {
            wdt_reset();
        }
    }
}

#endif
