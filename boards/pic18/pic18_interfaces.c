/* EasyLab PIC18 board: the transports of the debug and service interfaces
 * on the EUSART (portable C over pic18_hw.h). The part has one EUSART, so
 * a model has either the debug interface or Modbus RTU on it (the build
 * refuses both: a second UART the part lacks).
 *
 * Debug (runtime_c/el_debug.h): 8N1 at the model's baud rate, opened by
 * el_port_init. No transmit ring: a response goes out straight from the
 * server's buffer, and the transport's read takes nothing meanwhile (the
 * next request waits in the receive ring), so a write never finds the
 * transmitter busy unless the server's promise is broken; it is then
 * refused (the server counts it). Reset: the RESET instruction once the
 * reply is out; RESET_HALT survives it in el_pic18_kept.
 *
 * Modbus RTU (runtime_c/el_modbus_port.h): the model's baud rate and
 * parity, 8 data bits, 1 stop bit. A frame ends with a silence of 3.5
 * characters (1750 us above 19200 baud) after the last byte, measured on
 * the fine clock from the receive interrupt's time stamp. Replies are
 * queued whole. Modbus TCP needs a network: the board refuses it at build
 * time.
 */
#include "el_port.h"
#include "pic18_hw.h"

#if defined(EL_DEBUG) && EL_DEBUG && !(defined(EL_RELEASE) && EL_RELEASE)
#include "el_debug.h"
#endif

#if defined(EL_DEBUG_SERVER) && EL_DEBUG_SERVER && defined(EL_PIC18_DEBUG_BAUD)

uint16_t el_debug_port_read(uint8_t *buf, uint16_t max)
{
    return el_pic18_uart_read(buf, max);
}

bool el_debug_port_write(const uint8_t *frame, uint16_t len)
{
    return el_pic18_uart_write(frame, len, 0u);
}

bool el_debug_port_reset(uint8_t flags)
{
    uint32_t start;
    el_pic18_kept = (flags & EL_DBG_RESET_HALT) != 0u ? 0x5Au : 0u;
    /* Let the reply go out (a frame at 9600 baud takes 170 ms), then restart. */
    start = el_pic18_clock();
    while (el_pic18_clock() - start < 200u * (EL_PIC18_FCY / 1000u)) {
        el_pic18_watchdog_kick();
    }
    el_pic18_reset();
    return false;
}

#endif

#if defined(EL_PIC18_MODBUS)
#include "el_modbus_port.h"

static uint32_t mb_t35;  /* fine-clock cycles of a t3.5 silence */
static bool mb_in_frame; /* bytes were taken since the last silence */

uint8_t el_port_mb_rtu_open(uint8_t uart, uint32_t baud, uint8_t parity, uint8_t unit)
{
    uint8_t p = parity == EL_MB_PARITY_EVEN ? EL_PIC18_PARITY_EVEN
                : (parity == EL_MB_PARITY_ODD ? EL_PIC18_PARITY_ODD : EL_PIC18_PARITY_NONE);
    (void)unit;
    if (uart != 0u || baud == 0u) {
        return EL_MB_PORT_OFF;
    }
    el_pic18_uart_open(baud, p);
    /* 3.5 characters of 11 bits; a fixed 1750 us above 19200 baud. */
    mb_t35 = baud > 19200u ? 1750u * (EL_PIC18_FCY / 1000000u)
                           : (uint32_t)38500u * (EL_PIC18_FCY / 1000u) / baud;
    mb_in_frame = false;
    return EL_MB_PORT_TIMED;
}

int16_t el_port_mb_rtu_getc(void)
{
    int16_t c = el_pic18_uart_getc();
    if (c >= 0) {
        mb_in_frame = true;
        return c;
    }
    if (mb_in_frame) {
        /* The time stamp first: a byte arriving after it shows in the ring. */
        uint32_t last = el_pic18_uart_last_rx();
        if (el_pic18_uart_available() == 0u && el_pic18_clock() - last >= mb_t35) {
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
        if (chunk > (uint16_t)(EL_PIC18_UART_TX / 2u)) {
            chunk = (uint16_t)(EL_PIC18_UART_TX / 2u);
        }
        if (el_pic18_uart_write(adu + done, chunk, 200u)) {
            done = (uint16_t)(done + chunk);
        } else {
            el_pic18_watchdog_kick();
        }
    }
}

#endif
