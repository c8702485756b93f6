/* An MCP3201-class 12-bit SPI ADC: two bytes clocked in, the null bit
 * then B11..B0 from the second clock edge on. */
EL_OPEN {
    (void)el_spi_open(0u, EL_CS);
}

EL_READ {
    uint8_t rx[2];
    if (el_spi_transfer(0u, EL_CS, EL_SPI_MODE0, 0, rx, 2u) == EL_BUS_DONE) {
        value = (uint16_t)(((((uint16_t)rx[0] << 8) | rx[1]) >> 1) & 0x0FFFu);
    }
}
