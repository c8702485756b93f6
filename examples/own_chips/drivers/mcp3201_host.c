/* The MCP3201 simulated on the host (the host board and local execution):
 * the stimulus gives the count, as the simulators give it to the chip
 * model; 12 bits are all the chip has. */

EL_READ {
    value = (uint16_t)(value & 0x0FFFu); /* the stimulus value on entry */
}
