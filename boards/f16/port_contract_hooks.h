/* The f16 board's side of the port contract program
 * (tests/boards/port_contract.c, docs/boards.md "Adding a board"). The F2MC-16
 * runs nowhere here, so the program runs on the 16-bit proxy: f16_port.c's
 * logic over the 8051's hardware layer (proxy/f16p_hw.c) in s51. Its report
 * goes to the simulator interface's output file; Timer 1, free running at
 * the machine cycle (0.25 us at 48 MHz), is the fine clock; EA is the
 * interrupt state. */
#ifndef PORT_CONTRACT_HOOKS_H
#define PORT_CONTRACT_HOOKS_H

#include <8052.h>
#include "f16p.h"
#include "el_f16_config.h"

#define PC_NV_SIZE EL_F16P_NV_SIZE
/* Machine cycles on Timer 1, 16 bits, wrapping: spans shorter than 16 ms. */
typedef uint16_t pc_clock_t;
#define PC_CLOCK_PER_TICK ((pc_clock_t)4000u)
/* The tick interrupt is exact; a wait sees it within a pass of its loop,
 * some hundred machine cycles of sdcc's reentrant code. */
#define PC_EXACT_TICKS 1
#define PC_TICK_TOLERANCE 500u
#define PC_HAS_INTERRUPTS 1

static void pc_console_init(void)
{
    TR1 = 0;
    TMOD = (uint8_t)((TMOD & 0x0Fu) | 0x10u); /* Timer 1: mode 1, 16 bits */
    TH1 = 0u;
    TL1 = 0u;
    TR1 = 1;
}

static void pc_out_str(const char *s)
{
    while (*s != '\0') { /* straight to the interface: printing takes no tick */
        EL_F16P_SIF = EL_F16P_SIF_WRITE;
        EL_F16P_SIF = (uint8_t)*s++;
    }
}

static void pc_out_flush(void)
{
}

static pc_clock_t pc_clock_now(void)
{
    uint8_t hi, lo;
    do {
        hi = TH1;
        lo = TL1;
    } while (hi != TH1);
    return (pc_clock_t)((uint16_t)((uint16_t)hi << 8) | lo);
}

static int pc_irq_enabled(void)
{
    return EA ? 1 : 0;
}

#endif /* PORT_CONTRACT_HOOKS_H */
