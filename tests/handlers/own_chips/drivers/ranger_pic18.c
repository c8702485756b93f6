/* The range finder on the PIC18's EUSART (its one UART): the query byte
 * out, the 4-byte frame back within RANGER_WAIT_US, the millimetres made
 * cm. A frame that does not come or does not add up leaves the value. */
#define RANGER_BAUD 115200UL
#define RANGER_WAIT_CYCLES (EL_PIC18_FCY / 500u) /* 2 ms */

static bool ranger_frame_ok(const uint8_t *f)
{
    return f[0] == 0xFFu && (uint8_t)(f[0] + f[1] + f[2]) == f[3];
}

EL_OPEN {
    el_pic18_uart_open(RANGER_BAUD, EL_PIC18_PARITY_NONE);
}

EL_READ {
    static const uint8_t query = 0x55u;
    uint8_t frame[4];
    uint8_t got = 0u;
    uint32_t start = el_pic18_clock();
    while (el_pic18_uart_getc() >= 0) { /* a late frame of an earlier query */
    }
    if (el_pic18_uart_write(&query, 1u, 1u)) {
        while (got < 4u && el_pic18_clock() - start < RANGER_WAIT_CYCLES) {
            int16_t c = el_pic18_uart_getc();
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
