/* EasyLab AVR board, simulator harness: what the host board's trace and
 * stimulus code (boards/host/host_trace.c, host_stimulus.c, shared so that
 * files are the same byte for byte) need from their board. */
#include "host_internal.h"

#include <stdio.h>

const char *el_host_prog = "easylab-avr-sim";

/* The logical time of the instant the firmware is at (avr_sim.c sets it). */
uint64_t el_sim_now_us;

uint64_t el_host_now_us(void)
{
    return el_sim_now_us;
}
