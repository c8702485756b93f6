/* The humidity sensor in the simulator: a register pointer written first,
 * then its 16-bit registers read most significant byte first. */
#include "el_chip.h"

typedef struct {
    uint16_t reg[2]; /* 0: humidity, 0.01 %RH; 1: its identity */
    uint8_t pointer;
    uint8_t written; /* bytes written in this transaction */
    uint8_t read;    /* bytes read since the pointer was set */
} hygro_t;

static void reset(el_chip_t *chip)
{
    hygro_t *s = chip->state;
    s->reg[1] = 0x4859u;
}

static bool set_value(el_chip_t *chip, uint8_t k, const el_chip_value_t *v)
{
    hygro_t *s = chip->state;
    (void)k;
    if (v->i < 0 || v->i > 10000) {
        el_chip_error(chip, "a humidity of %lld: the chip measures 0 .. 10000 (0.01 %%RH)", (long long)v->i);
        return false;
    }
    s->reg[0] = (uint16_t)v->i;
    return true;
}

static bool start(el_chip_t *chip, bool read)
{
    hygro_t *s = chip->state;
    s->written = 0u;
    if (read)
        s->read = 0u;
    return true;
}

static bool write_byte(el_chip_t *chip, uint8_t byte)
{
    hygro_t *s = chip->state;
    if (s->written++ == 0u)
        s->pointer = byte & 1u;
    return true;
}

static uint8_t read_byte(el_chip_t *chip)
{
    hygro_t *s = chip->state;
    uint16_t r = s->reg[s->pointer];
    return s->read++ % 2u == 0u ? (uint8_t)(r >> 8) : (uint8_t)r;
}

const el_chip_ops_t EL_CHIP = {
    .name = "hygro", .state_size = sizeof(hygro_t), .reset = reset,
    .value = set_value, .i2c_start = start, .i2c_write = write_byte, .i2c_read = read_byte,
};
