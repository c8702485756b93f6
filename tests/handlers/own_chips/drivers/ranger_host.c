/* The range finder on the host: the stimulus gives the chip's millimetres,
 * as the simulators give them to its chip model. */
EL_READ {
    distance = (uint16_t)((distance + 5u) / 10u);
    reads++;
}
