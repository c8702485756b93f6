/* The counting humidity sensor on a board: register 0 holds the humidity
 * in 0.01 %RH, most significant byte first (drivers/hygro_chip.c in the
 * simulators); the state counts the reads and keeps the last four. */
EL_READ {
    uint8_t reg = 0u;
    uint8_t rx[2];
    if (el_i2c_transfer(bus, address, &reg, 1u, rx, 2u) == EL_BUS_DONE) {
        uint16_t last = recent[(next + 3u) % 4u];
        humidity = (uint16_t)(((uint16_t)rx[0] << 8) | rx[1]);
        reads++;
        trend = (int8_t)(humidity > last ? 1 : humidity < last ? -1 : 0);
        rising = humidity > last;
        recent[next] = humidity;
        next = (uint8_t)((next + 1u) % 4u);
    } else {
        failures++;
    }
}
