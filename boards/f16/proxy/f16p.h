/* EasyLab f16 board, 16-bit proxy: what the proxy's 8051 files share.
 *
 * The proxy runs the port's own logic (f16_port.c) and the board-
 * independent code (model, runtime, schedule) on an 8051 in uCsim's s51,
 * compiled by sdcc (16-bit int, 32-bit long, C89): f16p_hw.c is the
 * hardware layer of f16_internal.h on the 8051, f16p_sim.c the
 * simulation's simulated devices, stimulus and trace.
 *
 * The program talks to the simulator through uCsim's simulator interface,
 * a byte of external RAM (s51 -I if=xram[0xffff],in=FILE,out=FILE): a
 * command byte written there, then its argument or answer. It reads the
 * stimulus stream from the interface's input file and writes its report
 * (the trace's instants, or the port contract program's text) to its
 * output file; the host side (f16p_run.c) writes and reads them.
 *
 * Stream formats (little-endian, as sdcc lays out the 8051's memory):
 *   input:  "EL16", end tick (u32: the run ends at the first instant at or
 *           after it), then events: 'e', tick (u32), item (u16), first
 *           (u16), n (u16), size (u8), value (size bytes); sorted by tick.
 *   output: "EL16", 0x1234 (u16), 0x12345678 (u32), 1.5f (float): the
 *           host side checks the layout; then per instant 'I', tick (u32),
 *           every item's values in el_items order, every chart's step
 *           flags; at the end 'X'.
 */
#ifndef F16P_H
#define F16P_H

#include "el_types.h"

#define EL_F16P_SIF (*(volatile __xdata uint8_t *)0xFFFFu)

/* uCsim's simulator interface commands. */
#define EL_F16P_SIF_STOP 's'
#define EL_F16P_SIF_FIN_CHECK 'f'
#define EL_F16P_SIF_READ 'r'
#define EL_F16P_SIF_WRITE 'w'

void el_f16p_out(uint8_t c);
void el_f16p_out_bytes(const void *data, uint16_t n);
/* The next byte of the input file, or -1 at its end. */
int16_t el_f16p_in(void);
/* Stop the simulator (its console then goes on with the next command). */
void el_f16p_stop(void);

/* Simulation builds (f16p_sim.c): open the streams, the instant's hooks,
 * the end of the run. */
void el_f16p_sim_init(void);
bool el_f16p_sim_run_on(uint32_t tick);
void el_f16p_sim_inputs(el_tick_t tick);
void el_f16p_sim_instant(el_tick_t tick);
void el_f16p_sim_end(void);

/* The mailbox of device `out` data (generated el_f16p_tables.c): the
 * stimulus's latest values, copied into the data when the device is read. */
extern uint8_t el_f16p_mailbox[];
extern uint8_t el_f16p_mail_set[];
extern const uint16_t el_f16p_mail_at[];
extern const uint16_t el_f16p_set_at[];

#endif /* F16P_H */
