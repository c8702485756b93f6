/* The counting humidity sensor on the host board and in local execution:
 * humidity holds the stimulus's value; the state counts as on a board. */
EL_READ {
    uint16_t last = recent[(next + 3u) % 4u];
    reads++;
    trend = (int8_t)(humidity > last ? 1 : humidity < last ? -1 : 0);
    rising = humidity > last;
    recent[next] = humidity;
    next = (uint8_t)((next + 1u) % 4u);
}
