/* The MCP3201 on the AVR's SPI bus (runtime_c/el_bus.h). Its 16 clocks
 * give two sampling clocks, a null bit, then the 12 bits, most significant
 * first: xx0B BBBB BBBB BBBx. */

EL_OPEN {
    (void)el_spi_open(bus, EL_CS); /* the chip select an output, high */
}

EL_READ {
    uint8_t rx[2];
    if (el_spi_transfer(bus, EL_CS, EL_SPI_MODE0, (const uint8_t *)0, rx, 2u) == EL_BUS_DONE) {
        value = (uint16_t)((uint16_t)(rx[0] & 0x1Fu) << 7 | rx[1] >> 1);
    }
}
