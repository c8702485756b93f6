/* EasyLab AVR board: the link of a remote-execution proxy
 * (runtime_c/el_remote.h, docs/remote.md).
 *
 * The link is the UART el_avr_config.h names EL_AVR_REMOTE_UART (the first
 * one no device claims), 8N1 at EL_REMOTE_BAUD (easylab proxy --baud),
 * opened by el_port_init; bytes go through the board's UART rings
 * (avr_uart.c). A frame waits for room in the transmit ring as long as a
 * full ring takes to send, else it is dropped (the host counts it missing;
 * its CRC guards the rest).
 *
 * STOP from the host ends the session: once STOP's answer is on its way,
 * the watchdog restarts the MCU, whose boot drives the actuators to their
 * safe values and waits for the next host's START (tick 0 again). Only a
 * proxy build (easylab proxy: -DEL_REMOTE_PROXY=1) has any of this.
 */
#include "avr_internal.h"

#if defined(EL_REMOTE_PROXY) && EL_REMOTE_PROXY

#include "el_remote.h"

#include <avr/wdt.h>

#if !defined(EL_AVR_REMOTE_UART) || !defined(EL_REMOTE_BAUD)
#error "a proxy build names its link's UART (el_avr_config.h) and baud rate (-DEL_REMOTE_BAUD): easylab proxy"
#endif

/* Milliseconds to send a full transmit ring (10 bits a byte), rounded up. */
#define TX_WAIT_MS ((uint16_t)((uint32_t)EL_AVR_REMOTE_TX * 10000UL / (uint32_t)EL_REMOTE_BAUD + 2UL))

uint16_t el_remote_port_read(uint8_t *buf, uint16_t max)
{
    return el_avr_uart_read(EL_AVR_REMOTE_UART, buf, max);
}

bool el_remote_port_write(const uint8_t *frame, uint16_t len)
{
    return el_avr_uart_write(EL_AVR_REMOTE_UART, frame, len, TX_WAIT_MS);
}

bool el_remote_port_stopping(void)
{
    return false; /* an MCU runs until reset */
}

void el_remote_port_end(void)
{
    /* STOP's answer drains from the ring (interrupts stay on) while the
     * watchdog runs out. */
    wdt_enable(WDTO_30MS);
    for (;;) {
    }
}

#else
typedef int el_avr_remote_not_a_proxy_t; /* ISO C: a translation unit declares something */
#endif
