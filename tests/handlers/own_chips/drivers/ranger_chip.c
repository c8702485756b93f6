/* The range finder in the simulator: each query byte 0x55 it takes on its
 * UART is answered with a frame 0xFF, the distance in millimetres (the
 * stimulus value of the device's `distance`) high byte, low byte, and the
 * low byte of the sum of the three. */
#include "el_chip.h"

#define RANGER_QUERY 0x55u
#define RANGER_HEADER 0xFFu

typedef struct {
    uint16_t mm;
} ranger_t;

static bool set_value(el_chip_t *chip, uint8_t k, const el_chip_value_t *v)
{
    ranger_t *s = chip->state;
    (void)k;
    if (v->i < 30 || v->i > 4500) {
        el_chip_error(chip, "a distance of %lld mm: the chip measures 30 .. 4500", (long long)v->i);
        return false;
    }
    s->mm = (uint16_t)v->i;
    return true;
}

static void take_byte(el_chip_t *chip, uint8_t byte)
{
    ranger_t *s = chip->state;
    uint8_t high = (uint8_t)(s->mm >> 8), low = (uint8_t)s->mm;
    if (byte != RANGER_QUERY)
        return;
    el_chip_uart_send(chip, RANGER_HEADER);
    el_chip_uart_send(chip, high);
    el_chip_uart_send(chip, low);
    el_chip_uart_send(chip, (uint8_t)(RANGER_HEADER + high + low));
}

const el_chip_ops_t EL_CHIP = {
    .name = "ranger", .state_size = sizeof(ranger_t), .value = set_value, .uart_byte = take_byte,
};
