/* The humidity sensor on the AVR's I2C bus: its id at open, its count at
 * each read, 0..65535 for 0..100 %RH, in 0.1 %RH. */

static uint16_t hum16_tenths(uint16_t count)
{
    return (uint16_t)((uint32_t)count * 1000u / 65535u);
}

EL_OPEN {
    static const uint8_t id_pointer = 0x00u;
    uint8_t id[2];
    if (el_i2c_transfer(bus, address, &id_pointer, 1u, id, 2u) != EL_BUS_DONE || id[0] != 0x5Au) {
        failures++;
    }
}

EL_READ {
    static const uint8_t pointer = 0x01u;
    uint8_t reg[2];
    if (el_i2c_transfer(bus, address, &pointer, 1u, reg, 2u) == EL_BUS_DONE) {
        humidity = hum16_tenths((uint16_t)((uint16_t)reg[0] << 8 | reg[1]));
    } else {
        failures++;
    }
}
