/* The PIC18 board's side of the port contract program
 * (tests/boards/port_contract.c, docs/boards.md "Adding a board"): the
 * EUSART, polled, for the report (the board's ring is not compiled in);
 * the fine clock's instruction cycles (Timer1) as the clock; GIE as the
 * interrupt state. Portable C over pic18_hw.h, as every file the lowering
 * reads. */
#ifndef PORT_CONTRACT_HOOKS_H
#define PORT_CONTRACT_HOOKS_H

#include "pic18_hw.h"

#define PC_NV_SIZE EL_PIC18_NV_SIZE
/* Instruction cycles, 16 bits, wrapping: spans shorter than 6.5 ms. */
typedef uint16_t pc_clock_t;
#define PC_CLOCK_PER_TICK ((pc_clock_t)(EL_PIC18_FCY / 1000UL))
/* Ticks are exact (no drift); the port sees a tick within one turn of its
 * polling loop (el_port_wait_tick: the watchdog, the tick counter, el_idle),
 * well under 20 us. */
#define PC_EXACT_TICKS 1
#define PC_TICK_TOLERANCE 200u
#define PC_HAS_INTERRUPTS 1

static void pc_console_init(void)
{
}

static void pc_out_str(const char *s)
{
    while (*s != '\0') {
        el_pic18_uart_putc_polled((uint8_t)*s++);
    }
}

static void pc_out_flush(void)
{
    el_pic18_uart_flush_polled();
}

static pc_clock_t pc_clock_now(void)
{
    return (pc_clock_t)el_pic18_clock();
}

static int pc_irq_enabled(void)
{
    return el_pic18_irq_enabled() ? 1 : 0;
}

#endif /* PORT_CONTRACT_HOOKS_H */
