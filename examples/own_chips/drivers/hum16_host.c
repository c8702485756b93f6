/* The humidity sensor simulated on the host: the stimulus gives the
 * chip's count, as the simulators give it to the chip model; the handler
 * converts it the way the AVR's handler converts what it reads. */

static uint16_t hum16_tenths(uint16_t count)
{
    return (uint16_t)((uint32_t)count * 1000u / 65535u);
}

EL_READ {
    humidity = hum16_tenths(humidity); /* the stimulus value on entry */
}
