/* The shift register on the host: the stimulus gives the levels of its
 * inputs, as the simulators give them to its chip model; a closed switch
 * pulls its input low. */
EL_READ {
    closed = (uint8_t)~closed;
    reads++;
}
