/* EasyLab AVR driver "i2c_temperature" (std's I2cTemperature): an LM75 /
 * TMP102-class sensor on the I2C bus (runtime_c/el_bus.h, avr_twi.c).
 *
 * read() writes the register pointer 0 (temperature) and reads the
 * register's two bytes, most significant first: a left-justified two's
 * complement temperature, 1/256 degC per bit; the datum is the register
 * shifted right by 4, in 1/16 degC (the TMP102's 12-bit count; an LM75's
 * 9 bits give multiples of 8). The transfer finishes within the read, at
 * most EL_I2C_WAIT_US; a failed one (no acknowledge, timeout) leaves the
 * datum as it was and is counted (el_i2c_errors). The chip converts on its
 * own (TMP102: 4 times a second), so open() configures nothing. */
#ifndef EL_DRV_I2C_TEMPERATURE_H
#define EL_DRV_I2C_TEMPERATURE_H

#include "el_bus.h"
#include "el_driver.h"

typedef struct {
    uint8_t bus;          /* i2c[bus] */
    uint8_t address;      /* 0x48..0x4F */
    int16_t *temperature; /* `out int16`, 1/16 degC */
} el_drv_i2c_temperature_t;

EL_DRV_NOTHING(el_drv_i2c_temperature_open, el_drv_i2c_temperature_t)
EL_DRV_NOTHING(el_drv_i2c_temperature_start, el_drv_i2c_temperature_t)

static inline void el_drv_i2c_temperature_read(const el_drv_i2c_temperature_t *d)
{
    static const uint8_t pointer = 0u; /* the temperature register */
    uint8_t reg[2];
    if (el_i2c_transfer(d->bus, d->address, &pointer, 1u, reg, 2u) == EL_BUS_DONE) {
        *d->temperature = (int16_t)((int16_t)(uint16_t)((uint16_t)reg[0] << 8 | reg[1]) >> 4);
    }
}

EL_DRV_NOTHING(el_drv_i2c_temperature_write, el_drv_i2c_temperature_t)
EL_DRV_NOTHING(el_drv_i2c_temperature_stop, el_drv_i2c_temperature_t)
EL_DRV_NOTHING(el_drv_i2c_temperature_close, el_drv_i2c_temperature_t)

#endif /* EL_DRV_I2C_TEMPERATURE_H */
