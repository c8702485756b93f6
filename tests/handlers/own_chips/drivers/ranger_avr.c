/* The range finder on the AVR's USART `uart`: the query byte out, the
 * 4-byte frame back within RANGER_WAIT_US, the millimetres made cm. A
 * frame that does not come or does not add up leaves the value. */
#include "avr_internal.h"

#define RANGER_BAUD 115200UL
#define RANGER_WAIT_US 2000u

static bool ranger_frame_ok(const uint8_t *f)
{
    return f[0] == 0xFFu && (uint8_t)(f[0] + f[1] + f[2]) == f[3];
}

EL_OPEN {
    el_avr_uart_open(uart, RANGER_BAUD, EL_AVR_PARITY_NONE);
}

EL_READ {
    static const uint8_t query = 0x55u;
    uint8_t frame[4];
    uint8_t got = 0u;
    uint32_t start = el_avr_clock();
    while (el_avr_uart_getc(uart) >= 0) { /* a late frame of an earlier query */
    }
    if (el_avr_uart_write(uart, &query, 1u, 1u)) {
        while (got < 4u && el_avr_clock() - start < el_avr_clock_from_us(RANGER_WAIT_US)) {
            int16_t c = el_avr_uart_getc(uart);
            if (c >= 0) {
                frame[got++] = (uint8_t)c;
            }
        }
    }
    if (got == 4u && ranger_frame_ok(frame)) {
        distance = (uint16_t)(((((uint16_t)frame[1] << 8) | frame[2]) + 5u) / 10u);
        reads++;
    }
}
