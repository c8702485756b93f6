/* A humidity sensor on I2C: register 0 holds the humidity in 0.01 %RH,
 * most significant byte first. */
EL_READ {
    uint8_t reg = 0u;
    uint8_t rx[2];
    if (el_i2c_transfer(bus, address, &reg, 1u, rx, 2u) == EL_BUS_DONE) {
        humidity = (uint16_t)(((uint16_t)rx[0] << 8) | rx[1]);
    } else {
        failures++;
    }
}
