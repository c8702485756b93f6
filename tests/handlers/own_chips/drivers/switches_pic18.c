/* The shift register on the PIC18's port pins: a low pulse on the load
 * pin, then eight bits read from the data pin, input 7 first, a clock
 * pulse after each. A closed switch reads low. */

/* The hardware layer's number of a pin "PD5" (or "RD5"): port << 3 | bit. */
static el_pic18_pin_t switches_pin(const char *pin)
{
    return (el_pic18_pin_t)(((uint8_t)(pin[1] - 'A') << 3) | (uint8_t)(pin[2] - '0'));
}

EL_OPEN {
    el_pic18_pin_output(switches_pin(load_pin));
    el_pic18_pin_write(switches_pin(load_pin), true);
    el_pic18_pin_output(switches_pin(clock_pin));
    el_pic18_pin_input(switches_pin(data_pin));
}

EL_READ {
    uint8_t levels = 0u;
    uint8_t k;
    el_pic18_pin_write(switches_pin(load_pin), false);
    el_pic18_pin_write(switches_pin(load_pin), true);
    for (k = 0u; k < 8u; k++) {
        levels = (uint8_t)(levels << 1);
        if (el_pic18_pin_read(switches_pin(data_pin))) {
            levels |= 1u;
        }
        el_pic18_pin_write(switches_pin(clock_pin), true);
        el_pic18_pin_write(switches_pin(clock_pin), false);
    }
    closed = (uint8_t)~levels;
    reads++;
}
