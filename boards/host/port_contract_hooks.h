/* The host board's side of the port contract program
 * (tests/boards/port_contract.c, docs/boards.md "Adding a board"): where
 * the program prints, its fine clock, and what it can tell of interrupts.
 * A process has no interrupts to mask: the checks that look at them pass
 * trivially here and really on the boards that have them. */
#ifndef PORT_CONTRACT_HOOKS_H
#define PORT_CONTRACT_HOOKS_H

#include <stdio.h>
#include <time.h>

#define PC_NV_SIZE EL_HOST_NV_SIZE
/* The clock counts nanoseconds; a tick is 1 ms. */
typedef uint64_t pc_clock_t;
#define PC_CLOCK_PER_TICK ((pc_clock_t)1000000u)
/* Real time on a loaded machine: consecutive ticks are checked over 20
 * ticks within 25 %, not one by one. */
#define PC_EXACT_TICKS 0
/* Interrupt state: none to see (-1), none to mask. */
#define PC_HAS_INTERRUPTS 0

static void pc_console_init(void)
{
}

static void pc_out_str(const char *s)
{
    fputs(s, stdout);
}

static void pc_out_flush(void)
{
    fflush(stdout);
}

static pc_clock_t pc_clock_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (pc_clock_t)ts.tv_sec * 1000000000u + (pc_clock_t)ts.tv_nsec;
}

static int pc_irq_enabled(void)
{
    return -1;
}

#endif /* PORT_CONTRACT_HOOKS_H */
