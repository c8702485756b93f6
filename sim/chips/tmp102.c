/* EasyLab std chip model (el_chip.h): an LM75 / TMP102-class temperature
 * sensor on I2C, at the address 0x48..0x4F a device claims when its type
 * brings no chip model of its own (docs/boards.md, "Chip models").
 *
 * Registers temperature (0), configuration (1), T_LOW (2) and T_HIGH (3)
 * behind a pointer register (the first byte a write carries), each read
 * most significant byte first; a write of two more bytes sets one of the
 * last three. The temperature is value 0, the stimulus of the device's
 * first integer `out` datum, in 1/16 degC (the TMP102's 12-bit count;
 * -55 .. +150 degC); the register holds it left-justified, or in the
 * TMP102's 13-bit extended mode when the configuration's EM bit is set. It
 * follows the stimulus at once (a TMP102 converts 4 times a second).
 */
#include "el_chip.h"

#define TEMP_MIN (-55 * 16)
#define TEMP_MAX (150 * 16)
#define CONFIG_EM 0x0010u

typedef struct {
    uint8_t pointer;
    uint16_t reg[4];     /* temperature (unused: from sixteenths), configuration, T_LOW, T_HIGH */
    int32_t sixteenths;
    uint8_t index;       /* bytes written since the address */
    uint8_t byte_of_reg; /* the next byte of a register read: 0 MSB, 1 LSB */
    uint8_t written_hi;
} tmp102_t;

static void reset(el_chip_t *chip)
{
    tmp102_t *s = chip->state;
    s->reg[1] = 0x60A0u; /* the TMP102's power-on configuration */
    s->reg[2] = 0x4B00u; /* 75 degC */
    s->reg[3] = 0x5000u; /* 80 degC */
}

static bool value(el_chip_t *chip, uint8_t k, const el_chip_value_t *v)
{
    tmp102_t *s = chip->state;
    int64_t t = v->is_float ? (int64_t)v->f : v->i;
    if (t < TEMP_MIN || t > TEMP_MAX) {
        el_chip_error(chip, "%s = %lld: the TMP102-class sensor at i2c[%u] 0x%02x measures -55 .. 150 degC "
                            "(-880 .. 2400 sixteenths)", chip->value_names[k], (long long)t, (unsigned)chip->bus,
                      (unsigned)chip->address);
        return false;
    }
    s->sixteenths = (int32_t)t;
    return true;
}

static uint16_t temperature_register(const tmp102_t *s)
{
    int32_t t = s->sixteenths;
    if (s->reg[1] & CONFIG_EM) { /* 13 bits, then the EM flag in bit 0 */
        t = t < -4096 ? -4096 : t > 4095 ? 4095 : t;
        return (uint16_t)((uint16_t)((uint32_t)t << 3) | 1u);
    }
    t = t < -2048 ? -2048 : t > 2047 ? 2047 : t;
    return (uint16_t)((uint32_t)t << 4);
}

static bool i2c_start(el_chip_t *chip, bool read)
{
    tmp102_t *s = chip->state;
    (void)read;
    s->index = 0u;
    s->byte_of_reg = 0u;
    return true;
}

static bool i2c_write(el_chip_t *chip, uint8_t b)
{
    tmp102_t *s = chip->state;
    if (s->index == 0u) {
        s->pointer = b & 3u;
    } else if (s->index == 1u) {
        s->written_hi = b;
    } else if (s->index == 2u && s->pointer != 0u) { /* the temperature register is read-only */
        s->reg[s->pointer] = (uint16_t)((uint16_t)s->written_hi << 8 | b);
    }
    if (s->index < 255u)
        s->index++;
    return true;
}

static uint8_t i2c_read(el_chip_t *chip)
{
    tmp102_t *s = chip->state;
    uint16_t r = s->pointer == 0u ? temperature_register(s) : s->reg[s->pointer];
    uint8_t b = s->byte_of_reg == 0u ? (uint8_t)(r >> 8) : (uint8_t)r;
    s->byte_of_reg ^= 1u;
    return b;
}

const el_chip_ops_t EL_CHIP = {
    .name = "tmp102",
    .state_size = sizeof(tmp102_t),
    .reset = reset,
    .value = value,
    .i2c_start = i2c_start,
    .i2c_write = i2c_write,
    .i2c_read = i2c_read,
};
