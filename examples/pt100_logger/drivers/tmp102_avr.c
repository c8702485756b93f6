/* The TMP102 on the AVR's I2C bus (runtime_c/el_bus.h): its 13-bit extended
 * mode, the temperature in 0.1 degC. Device handlers: docs/language.md,
 * "Device handlers"; docs/boards.md, "Writing a device driver". */

/* 1/16 degC (the chip's count) to 0.1 degC, rounded toward zero. */
static int16_t tmp102_tenths(int16_t count)
{
    return (int16_t)((int32_t)count * 10 / 16);
}

EL_OPEN {
    /* The configuration register: 4 conversions a second, extended mode. */
    static const uint8_t config[3] = {0x01u, 0x60u, 0xB0u};
    if (el_i2c_transfer(bus, address, config, 3u, (uint8_t *)0, 0u) != EL_BUS_DONE) {
        failures++;
    }
}

EL_READ {
    static const uint8_t pointer = 0x00u; /* the temperature register */
    uint8_t reg[2];
    if (el_i2c_transfer(bus, address, &pointer, 1u, reg, 2u) == EL_BUS_DONE) {
        /* 13 bits, left-justified; bit 0 is the extended-mode flag */
        int16_t raw = (int16_t)(uint16_t)((uint16_t)reg[0] << 8 | reg[1]);
        temperature = tmp102_tenths((int16_t)((raw & ~7) / 8));
        reads++;
    } else {
        failures++;
    }
}
