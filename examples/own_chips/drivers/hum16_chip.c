/* The humidity sensor for the simulators (sim/el_chip.h): 16-bit registers
 * behind a pointer (the first byte a write carries), read most significant
 * byte first: 0 the id 0x5A01, 1 the humidity's count (the stimulus of the
 * device's `humidity`, 0..65535), 2 a configuration register the firmware
 * may write. */
#include "el_chip.h"

typedef struct {
    uint16_t reg[3];
    uint8_t pointer;
    uint8_t index;  /* bytes written since the address */
    uint8_t half;   /* the next byte of a read: 0 MSB, 1 LSB */
    uint8_t high;   /* a written register's MSB */
} hum16_t;

static void hum16_reset(el_chip_t *chip)
{
    hum16_t *s = chip->state;
    s->reg[0] = 0x5A01u;
}

static bool hum16_value(el_chip_t *chip, uint8_t k, const el_chip_value_t *v)
{
    hum16_t *s = chip->state;
    if (v->i < 0 || v->i > 65535) {
        el_chip_error(chip, "%s = %lld: the count is 0 .. 65535", chip->value_names[k], (long long)v->i);
        return false;
    }
    s->reg[1] = (uint16_t)v->i;
    return true;
}

static bool hum16_start(el_chip_t *chip, bool read)
{
    hum16_t *s = chip->state;
    (void)read;
    s->index = 0u;
    s->half = 0u;
    return true;
}

static bool hum16_write(el_chip_t *chip, uint8_t b)
{
    hum16_t *s = chip->state;
    if (s->index == 0u) {
        if (b > 2u)
            return false; /* no such register: not acknowledged */
        s->pointer = b;
    } else if (s->index == 1u) {
        s->high = b;
    } else if (s->index == 2u && s->pointer == 2u) {
        s->reg[2] = (uint16_t)((uint16_t)s->high << 8 | b);
    }
    if (s->index < 3u)
        s->index++;
    return true;
}

static uint8_t hum16_read(el_chip_t *chip)
{
    hum16_t *s = chip->state;
    uint16_t r = s->reg[s->pointer];
    uint8_t b = s->half == 0u ? (uint8_t)(r >> 8) : (uint8_t)r;
    s->half ^= 1u;
    return b;
}

const el_chip_ops_t EL_CHIP = {
    .name = "hum16",
    .state_size = sizeof(hum16_t),
    .reset = hum16_reset,
    .value = hum16_value,
    .i2c_start = hum16_start,
    .i2c_write = hum16_write,
    .i2c_read = hum16_read,
};
