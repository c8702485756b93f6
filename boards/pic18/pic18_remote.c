/* EasyLab PIC18 board: the link of a remote-execution proxy
 * (runtime_c/el_remote.h, docs/remote.md), in portable C over pic18_hw.h.
 *
 * The link is the EUSART (el_pic18_config.h: EL_PIC18_REMOTE_UART, when no
 * device claims it), 8N1 at EL_REMOTE_BAUD (easylab proxy --baud), opened
 * by el_port_init; bytes go through the board's UART rings (pic18_uart.c),
 * sized from the device model's frames. A frame waits for room in the
 * transmit ring as long as a full ring takes to send, else it is dropped
 * (the host counts it missing; its CRC guards the rest).
 *
 * STOP from the host ends the session: once STOP's answer has left the
 * ring, the RESET instruction restarts the MCU, whose boot drives the
 * actuators to their safe values and waits for the next host's START
 * (tick 0 again). Only a proxy build (-DEL_REMOTE_PROXY=1) has any of this.
 */
#include "el_port.h"
#include "pic18_hw.h"

#if defined(EL_REMOTE_PROXY) && EL_REMOTE_PROXY

#include "el_remote.h"

#if !defined(EL_PIC18_REMOTE_UART) || !defined(EL_REMOTE_BAUD)
#error "a proxy build names its link's UART (el_pic18_config.h) and baud rate (-DEL_REMOTE_BAUD): easylab proxy"
#endif

/* Milliseconds to send a full transmit ring (10 bits a byte), rounded up. */
#define TX_WAIT_MS ((uint16_t)((uint32_t)EL_PIC18_UART_TX * 10000UL / (uint32_t)EL_REMOTE_BAUD + 2UL))

uint16_t el_remote_port_read(uint8_t *buf, uint16_t max)
{
    return el_pic18_uart_read(buf, max);
}

bool el_remote_port_write(const uint8_t *frame, uint16_t len)
{
    return el_pic18_uart_write(frame, len, TX_WAIT_MS);
}

bool el_remote_port_stopping(void)
{
    return false; /* an MCU runs until reset */
}

void el_remote_port_end(void)
{
    /* STOP's answer drains from the ring (interrupts stay on), then the
     * last byte leaves the shift register. */
    uint32_t start = el_pic18_clock();
    while (el_pic18_clock() - start < (uint32_t)TX_WAIT_MS * (EL_PIC18_FCY / 1000u)) {
        el_pic18_watchdog_kick();
    }
    el_pic18_uart_flush_polled();
    el_pic18_reset();
}

#else
typedef int el_pic18_remote_not_a_proxy_t; /* ISO C: a translation unit declares something */
#endif
