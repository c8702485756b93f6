/* The MCP3201 for the simulators (sim/el_chip.h): the stimulus of the
 * device's `value` is the count it converts. Selected, it samples; then it
 * shifts out two sampling clocks (the line floats: 1), a null bit, the 12
 * bits most significant first, the same bits least significant first from
 * B1, then zeros. */
#include "el_chip.h"

typedef struct {
    uint16_t count;   /* the stimulus */
    uint16_t sampled; /* the count at the chip select's fall */
    uint8_t clock;    /* bits shifted out since */
} mcp3201_t;

static bool mcp3201_value(el_chip_t *chip, uint8_t k, const el_chip_value_t *v)
{
    mcp3201_t *s = chip->state;
    if (v->i < 0 || v->i > 4095) {
        el_chip_error(chip, "%s = %lld: a 12-bit ADC converts 0 .. 4095", chip->value_names[k], (long long)v->i);
        return false;
    }
    s->count = (uint16_t)v->i;
    return true;
}

static void mcp3201_select(el_chip_t *chip, bool selected)
{
    mcp3201_t *s = chip->state;
    if (selected) {
        s->sampled = s->count;
        s->clock = 0u;
    }
}

static unsigned mcp3201_bit(const mcp3201_t *s, unsigned n)
{
    if (n < 2u)
        return 1u;
    if (n == 2u)
        return 0u;
    if (n <= 14u)
        return (s->sampled >> (14u - n)) & 1u; /* B11 .. B0 */
    if (n <= 25u)
        return (s->sampled >> (n - 14u)) & 1u; /* B1 .. B11 */
    return 0u;
}

static uint8_t mcp3201_byte(el_chip_t *chip, uint8_t mosi)
{
    mcp3201_t *s = chip->state;
    uint8_t out = 0u;
    unsigned k;
    (void)mosi; /* the chip has no input */
    for (k = 0; k < 8u; k++)
        out = (uint8_t)(out << 1 | mcp3201_bit(s, s->clock + k));
    if (s->clock < 248u)
        s->clock = (uint8_t)(s->clock + 8u);
    return out;
}

const el_chip_ops_t EL_CHIP = {
    .name = "mcp3201",
    .state_size = sizeof(mcp3201_t),
    .value = mcp3201_value,
    .spi_select = mcp3201_select,
    .spi_byte = mcp3201_byte,
};
