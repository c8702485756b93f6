/* EasyLab PIC18 board: the port interface of runtime_c/el_port.h, in
 * portable C over the hardware layer (pic18_hw.h).
 *
 * Time: the tick counter of Timer2's interrupts (pic18_hw.c). Tick n is due
 * n ticks after el_port_init. el_port_wait_tick serves the interfaces
 * (el_idle) until the tick has come; a late tick returns at once (the
 * dispatcher counts lateness). The CPU polls rather than sleeping in idle
 * mode: gpsim 0.31 does not model idle mode (it stops Timer1, the fine
 * clock, in SLEEP whatever IDLEN says), and the simulation must be the
 * firmware that runs on the board.
 *
 * Critical sections save INTCON's GIE and clear it; restoring sets it
 * again only if it was set, so they nest.
 *
 * Simulation builds (EL_PIC18_SIM, `easylab build --sim`) tell the gpsim
 * harness (sim/) about instants through el_pic18_sim_mark, a byte whose
 * writes the harness watches: el_port_inputs stores the instant's tick in
 * el_pic18_sim_tick, writes EL_PIC18_SIM_INPUTS and waits while the
 * harness keeps el_pic18_sim_busy nonzero (it is delivering input: UART
 * bytes, encoder edges); el_port_instant writes EL_PIC18_SIM_INSTANT;
 * el_port_init writes EL_PIC18_SIM_BOOT (a RESET cleared the RAM). The
 * harness reads the items from RAM at that moment. Each iteration of the
 * wait loops writes EL_PIC18_SIM_WAIT or EL_PIC18_SIM_IDLE before it polls
 * (the harness's count of the cycles spent waiting). Other builds do
 * nothing there.
 */
#include "el_port.h"
#include "el_dispatch.h"
#include "pic18_hw.h"

#if defined(EL_DEBUG) && EL_DEBUG && !(defined(EL_RELEASE) && EL_RELEASE)
#include "el_debug.h" /* EL_DEBUG_SERVER: whether to open the debug UART */
#endif

#if defined(EL_PIC18_SIM) && EL_PIC18_SIM
#define SIM_SPIN(mark) (el_pic18_sim_mark = (uint8_t)(mark))
#else
#define SIM_SPIN(mark) ((void)0)
#endif

#if defined(EL_PIC18_SIM) && EL_PIC18_SIM
/* The instant being processed (32 bits, EL_TICK_32: the harness extends
 * it), its marks and the harness's busy flag: read and written by the
 * harness, at the addresses the linker gives them. */
volatile uint32_t el_pic18_sim_tick;
volatile uint8_t el_pic18_sim_mark;
volatile uint8_t el_pic18_sim_busy;
#endif

/* el_pic18_kept after a debugger's RESET with RESET_HALT (pic18_interfaces.c). */
#define KEPT_RESET_HALT 0x5Au

/* Is `cause` the debugger's RESET, for RESET_HALT? On the part, RCON says
 * so (after a power-on the kept byte is undefined). gpsim 0.31 does not
 * show the RESET instruction in RCON as the part does, and its RAM starts
 * zeroed: in a simulation build the kept byte alone says it. */
#if defined(EL_PIC18_SIM) && EL_PIC18_SIM
#define DEBUGGER_RESET(cause) ((void)(cause), true)
#else
#define DEBUGGER_RESET(cause) ((cause) == EL_PIC18_RESET_SOFTWARE)
#endif

bool el_port_init(int argc, char **argv)
{
    uint8_t cause;
    (void)argc;
    (void)argv;
    cause = el_pic18_start();
#if defined(EL_PIC18_SIM) && EL_PIC18_SIM
    el_pic18_sim_mark = EL_PIC18_SIM_BOOT; /* after a RESET too (a proxy's STOP): the stack's guard is gone */
#endif
#if defined(EL_PIC18_DEBUG_BAUD) && defined(EL_DEBUG_SERVER) && EL_DEBUG_SERVER
    el_pic18_uart_open(EL_PIC18_DEBUG_BAUD, EL_PIC18_PARITY_NONE);
    /* Halt at the first instant after a RESET with RESET_HALT only (after a
     * power-on the kept byte is undefined: the cause must be the RESET). */
    if (el_pic18_kept == KEPT_RESET_HALT && DEBUGGER_RESET(cause)) {
        el_debug_halt_at_start();
    }
#if defined(EL_PIC18_SIM) && EL_PIC18_SIM
    if (el_pic18_kept == EL_PIC18_SIM_HALT) { /* the harness's --halt */
        el_debug_halt_at_start();
    }
#endif
#else
    (void)cause;
#endif
#if defined(EL_REMOTE_PROXY) && EL_REMOTE_PROXY && defined(EL_PIC18_REMOTE_UART)
    el_pic18_uart_open(EL_REMOTE_BAUD, EL_PIC18_PARITY_NONE); /* the proxy's link (pic18_remote.c) */
#endif
    el_pic18_kept = 0u;
    return true;
}

bool el_port_wait_tick(uint32_t tick)
{
#if defined(EL_ROUND_SLAVE)
    for (;;) {
        el_pic18_watchdog_kick();
        el_idle(); /* the bus: the sync that lets the tick run */
        if (el_round_gate(tick) != 0) {
            return true;
        }
    }
#endif
    for (;;) {
        el_pic18_watchdog_kick();
        if ((int32_t)(el_pic18_ticks() - tick) >= 0) {
            return true;
        }
        SIM_SPIN(EL_PIC18_SIM_WAIT);
        el_idle();
    }
}

void el_port_idle(uint16_t max_ms)
{
    uint32_t start = el_pic18_clock();
    uint32_t span = (uint32_t)max_ms * (EL_PIC18_FCY / 1000u);
    do {
        el_pic18_watchdog_kick();
        SIM_SPIN(EL_PIC18_SIM_IDLE);
#if defined(EL_REMOTE_PROXY) && EL_REMOTE_PROXY && defined(EL_PIC18_REMOTE_UART)
        if (el_pic18_uart_available() != 0u) {
            el_idle();
            return; /* the link brought something: the proxy looks at once (a lock-step DOWN) */
        }
#endif
        el_idle();
    } while (el_pic18_clock() - start < span);
}

void el_port_resync(void)
{
    /* The current tick is due now: a fresh tick period starts. */
    el_pic18_resync((uint32_t)el_now_tick());
}

uint32_t el_port_real_tick(void)
{
    return el_pic18_ticks();
}

el_irq_state_t el_port_irq_save(void)
{
    return el_pic18_irq_save();
}

void el_port_irq_restore(el_irq_state_t state)
{
    el_pic18_irq_restore(state);
}

/* ---- instants ---- */

#if defined(EL_PIC18_SIM) && EL_PIC18_SIM

/* The tick first, in a function of its own: the mark is written after the
 * call returns (sdcc 4.2 moved a mark passed as a parameter in front of
 * the tick's stores, volatile or not). */
static void sim_tick_store(el_tick_t tick)
{
    el_pic18_sim_tick = (uint32_t)tick;
}
#endif

void el_port_inputs(el_tick_t tick)
{
#if defined(EL_PIC18_SIM) && EL_PIC18_SIM
    el_pic18_sim_busy = 0u;
    sim_tick_store(tick);
    el_pic18_sim_mark = EL_PIC18_SIM_INPUTS;
    while (el_pic18_sim_busy != 0u) { /* the harness is delivering input (interrupts on) */
        el_pic18_watchdog_kick();
    }
#else
    (void)tick;
#endif
}

void el_port_instant(el_tick_t tick)
{
#if defined(EL_PIC18_SIM) && EL_PIC18_SIM
    sim_tick_store(tick);
    el_pic18_sim_mark = EL_PIC18_SIM_INSTANT;
#else
    (void)tick;
#endif
}

void el_port_shutdown(void)
{
    /* An MCU run never ends. */
    el_pic18_stop();
}

/* ---- non-volatile storage: the data EEPROM, byte for byte from offset 0;
 * erased bytes read 0xFF; only bytes that change are programmed ---- */

bool el_port_nv_read(uint16_t offset, void *data, uint16_t size)
{
    uint8_t *p = (uint8_t *)data;
    uint16_t i;
    if ((uint32_t)offset + size > EL_PIC18_NV_SIZE || (data == (void *)0 && size != 0u)) {
        return false;
    }
    for (i = 0u; i < size; i++) {
        p[i] = el_pic18_eeprom_read((uint16_t)(offset + i));
    }
    return true;
}

bool el_port_nv_write(uint16_t offset, const void *data, uint16_t size)
{
    const uint8_t *p = (const uint8_t *)data;
    uint16_t i;
    if ((uint32_t)offset + size > EL_PIC18_NV_SIZE || (data == (const void *)0 && size != 0u)) {
        return false;
    }
    for (i = 0u; i < size; i++) {
        el_pic18_eeprom_update((uint16_t)(offset + i), p[i]);
    }
    return true;
}
