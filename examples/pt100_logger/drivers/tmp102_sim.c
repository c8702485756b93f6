/* The TMP102 simulated on the host (the host board and local execution):
 * the stimulus gives the chip's count in 1/16 degC, as the AVR's simulator
 * gives it to its TMP102 model; the handler converts it the way the AVR's
 * handler converts what it reads. */

static int16_t tmp102_tenths(int16_t count)
{
    return (int16_t)((int32_t)count * 10 / 16);
}

EL_READ {
    temperature = tmp102_tenths(temperature); /* the stimulus value on entry */
    reads++;
}
