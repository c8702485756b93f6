/* The shift register in the simulator: its eight inputs' levels are the
 * stimulus value of the device's `closed`. The load pin low latches them
 * (the first, input 7, on the data pin at once); with the load pin high,
 * each rising edge of the clock shifts the next one onto the data pin (a
 * low shifted in behind them). Pins in the order of the device's claims:
 * load, clock, data. */
#include "el_chip.h"

enum { LOAD, CLOCK, DATA }; /* chip->pins, in the order of the claims */

typedef struct {
    uint8_t inputs;
    uint8_t shift;  /* what is left to shift out, input 7 first */
    bool loading;   /* the load pin is low */
} switches_t;

static bool set_value(el_chip_t *chip, uint8_t k, const el_chip_value_t *v)
{
    switches_t *s = chip->state;
    (void)k;
    s->inputs = (uint8_t)v->i;
    return true;
}

static void output(el_chip_t *chip)
{
    switches_t *s = chip->state;
    el_chip_pin_drive(chip, chip->pins[DATA], (s->shift & 0x80u) != 0u);
}

static void edge(el_chip_t *chip, uint16_t pin, bool level)
{
    switches_t *s = chip->state;
    if (pin == chip->pins[LOAD]) {
        s->loading = !level;
        if (s->loading) {
            s->shift = s->inputs;
            output(chip);
        }
    } else if (pin == chip->pins[CLOCK] && level && !s->loading) {
        s->shift = (uint8_t)(s->shift << 1);
        output(chip);
    }
}

const el_chip_ops_t EL_CHIP = {
    .name = "switches", .state_size = sizeof(switches_t), .value = set_value, .pin_edge = edge,
};
