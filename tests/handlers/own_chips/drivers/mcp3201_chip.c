/* The MCP3201 in the simulator: it shifts out two zero bits, the null bit
 * and its 12-bit count, most significant first; the count is the
 * stimulus value of the device's `value`. */
#include "el_chip.h"

typedef struct {
    uint16_t count;
    uint16_t frame; /* the bits of the conversion under way */
    uint8_t byte;   /* bytes clocked since the chip select fell */
} mcp3201_t;

static bool set_value(el_chip_t *chip, uint8_t k, const el_chip_value_t *v)
{
    mcp3201_t *s = chip->state;
    (void)k;
    if (v->i < 0 || v->i > 4095) {
        el_chip_error(chip, "a count of %lld: the chip converts 0 .. 4095", (long long)v->i);
        return false;
    }
    s->count = (uint16_t)v->i;
    return true;
}

static void select_chip(el_chip_t *chip, bool selected)
{
    mcp3201_t *s = chip->state;
    if (selected) {
        s->frame = (uint16_t)(s->count << 1);
        s->byte = 0u;
    }
}

static uint8_t clock_byte(el_chip_t *chip, uint8_t mosi)
{
    mcp3201_t *s = chip->state;
    uint8_t out = s->byte == 0u ? (uint8_t)(s->frame >> 8) : (s->byte == 1u ? (uint8_t)s->frame : 0xFFu);
    (void)mosi;
    s->byte++;
    return out;
}

const el_chip_ops_t EL_CHIP = {
    .name = "mcp3201", .state_size = sizeof(mcp3201_t),
    .value = set_value, .spi_select = select_chip, .spi_byte = clock_byte,
};
