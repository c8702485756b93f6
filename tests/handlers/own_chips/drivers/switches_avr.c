/* The shift register on the AVR's port pins: a low pulse on the load pin,
 * then eight bits read from the data pin, input 7 first, a clock pulse
 * after each. A closed switch reads low. */
#include <avr/io.h>

/* PORTx of a pin "PD5" (the ATmega328P's ports B, C, D); DDRx is the
 * register below it, PINx the one below that. */
static volatile uint8_t *switches_port(const char *pin)
{
    return pin[1] == 'B' ? &PORTB : pin[1] == 'C' ? &PORTC : &PORTD;
}

static uint8_t switches_mask(const char *pin)
{
    return (uint8_t)(1u << (pin[2] - '0'));
}

static void switches_set(const char *pin, bool level)
{
    if (level) {
        *switches_port(pin) |= switches_mask(pin);
    } else {
        *switches_port(pin) &= (uint8_t)~switches_mask(pin);
    }
}

EL_OPEN {
    switches_set(load_pin, true);
    switches_set(clock_pin, false);
    *(switches_port(load_pin) - 1) |= switches_mask(load_pin);
    *(switches_port(clock_pin) - 1) |= switches_mask(clock_pin);
    *(switches_port(data_pin) - 1) &= (uint8_t)~switches_mask(data_pin);
}

EL_READ {
    uint8_t levels = 0u;
    uint8_t k;
    switches_set(load_pin, false);
    switches_set(load_pin, true);
    for (k = 0u; k < 8u; k++) {
        levels = (uint8_t)(levels << 1);
        if ((*(switches_port(data_pin) - 2) & switches_mask(data_pin)) != 0u) {
            levels |= 1u;
        }
        switches_set(clock_pin, true);
        switches_set(clock_pin, false);
    }
    closed = (uint8_t)~levels;
    reads++;
}
