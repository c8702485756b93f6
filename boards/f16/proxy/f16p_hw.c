/* EasyLab f16 board, 16-bit proxy: the hardware layer of f16_internal.h on
 * the 8052 that s51 simulates (f16p.h).
 *
 * - Tick: Timer 2 in 16-bit auto-reload mode counts machine cycles (four
 *   per microsecond: s51 runs the 8052 at 48 MHz, twelve clocks a cycle)
 *   and interrupts every EL_F16_TICK_PERIOD of them, as reload timer 0
 *   does on the part. So many cycles per tick leave sdcc's reentrant code
 *   time for an instant's work, as the part's 16 MHz does.
 * - Interrupts: EA, which the 8051 can read back.
 * - Non-volatile storage: EL_F16P_NV_SIZE bytes of external RAM, erased
 *   (0xFF) at boot, like the host board's store without --nvram.
 * - The end of a run stops the simulator.
 *
 * sdcc wants an interrupt function declared where main() is: main is here
 * (f16_port.c's is the part's).
 */
#include <8052.h>

#include "f16_internal.h"
#include "f16p.h"
#include "el_dispatch.h"
#include "el_modbus_port.h"

#if defined(EL_DEBUG) && EL_DEBUG && !(defined(EL_RELEASE) && EL_RELEASE)
#include "el_debug.h"
#endif

#define TIMER2_RELOAD ((uint16_t)(65536UL - EL_F16_TICK_PERIOD))

static uint8_t nv_store[EL_F16P_NV_SIZE];

void el_f16p_out(uint8_t c)
{
    EL_F16P_SIF = EL_F16P_SIF_WRITE;
    EL_F16P_SIF = c;
}

void el_f16p_out_bytes(const void *data, uint16_t n)
{
    const uint8_t *p = (const uint8_t *)data;
    uint16_t i;
    for (i = 0u; i < n; i++) {
        el_f16p_out(p[i]);
    }
}

int16_t el_f16p_in(void)
{
    EL_F16P_SIF = EL_F16P_SIF_FIN_CHECK;
    if (EL_F16P_SIF == 0u) {
        return -1;
    }
    EL_F16P_SIF = EL_F16P_SIF_READ;
    return EL_F16P_SIF;
}

void el_f16p_stop(void)
{
    EL_F16P_SIF = EL_F16P_SIF_STOP;
}

/* Register bank 1: the handler calls nothing, so nothing needs bank 0's
 * registers saved on the stack. */
void el_f16p_timer2_isr(void) __interrupt(5) __using(1) /* Timer 2 */
{
    TF2 = 0; /* Timer 2 leaves its flag to the program */
    EL_F16_TICK_ISR_BODY();
}

void el_f16_hw_init(void)
{
    uint16_t i;
    for (i = 0u; i < EL_F16P_NV_SIZE; i++) {
        nv_store[i] = 0xFFu;
    }
#if defined(EL_F16_PROXY_SIM)
    el_f16p_sim_init();
#endif
}

void el_f16_tick_timer_start(void)
{
    T2CON = 0u; /* auto-reload from RCAP2, stopped */
    RCAP2H = (uint8_t)(TIMER2_RELOAD >> 8);
    RCAP2L = (uint8_t)TIMER2_RELOAD;
    TH2 = RCAP2H;
    TL2 = RCAP2L;
    ET2 = 1;
    TR2 = 1;
}

void el_f16_tick_timer_restart(void)
{
    TR2 = 0;
    TH2 = RCAP2H;
    TL2 = RCAP2L;
    TF2 = 0;
    TR2 = 1;
}

uint16_t el_f16_tick_timer_elapsed(void)
{
    uint8_t hi, lo;
    do {
        hi = TH2;
        lo = TL2;
    } while (hi != TH2);
    return (uint16_t)((uint16_t)((uint16_t)hi << 8 | lo) - TIMER2_RELOAD);
}

bool el_f16_tick_timer_pending(void)
{
    return TF2 != 0;
}

el_irq_state_t el_f16_hw_irq_save(void)
{
    el_irq_state_t state = EA ? 1u : 0u;
    EA = 0;
    return state;
}

void el_f16_hw_irq_restore(el_irq_state_t state)
{
    EA = state != 0u;
}

void el_f16_hw_irq_on(void)
{
    EA = 1;
}

bool el_f16_hw_run_on(uint32_t tick)
{
#if defined(EL_F16_PROXY_SIM)
    return el_f16p_sim_run_on(tick);
#else
    (void)tick;
    return true;
#endif
}

void el_f16_hw_inputs(el_tick_t tick)
{
#if defined(EL_F16_PROXY_SIM)
    el_f16p_sim_inputs(tick);
#else
    (void)tick;
#endif
}

void el_f16_hw_instant(el_tick_t tick)
{
#if defined(EL_F16_PROXY_SIM)
    el_f16p_sim_instant(tick);
#else
    (void)tick;
#endif
}

bool el_f16_hw_nv_read(uint16_t offset, void *data, uint16_t size)
{
    uint8_t *p = (uint8_t *)data;
    uint16_t i;
    if (offset > EL_F16P_NV_SIZE || size > (uint16_t)(EL_F16P_NV_SIZE - offset)) {
        return false;
    }
    for (i = 0u; i < size; i++) {
        p[i] = nv_store[offset + i];
    }
    return true;
}

bool el_f16_hw_nv_write(uint16_t offset, const void *data, uint16_t size)
{
    const uint8_t *p = (const uint8_t *)data;
    uint16_t i;
    if (offset > EL_F16P_NV_SIZE || size > (uint16_t)(EL_F16P_NV_SIZE - offset)) {
        return false;
    }
    for (i = 0u; i < size; i++) {
        nv_store[offset + i] = p[i];
    }
    return true;
}

void el_f16_hw_shutdown(void)
{
    EA = 0;
#if defined(EL_F16_PROXY_SIM)
    el_f16p_sim_end();
#endif
    el_f16p_stop();
    for (;;) {
    }
}

/* ---- the interfaces: nothing arrives, replies go nowhere (the proxy
 * checks the model's behaviour, not its links) ---- */

#if defined(EL_DEBUG_SERVER) && EL_DEBUG_SERVER
uint16_t el_debug_port_read(uint8_t *buf, uint16_t max)
{
    (void)buf;
    (void)max;
    return 0u;
}

bool el_debug_port_write(const uint8_t *frame, uint16_t len)
{
    (void)frame;
    (void)len;
    return true;
}

bool el_debug_port_reset(uint8_t flags)
{
    (void)flags;
    return false;
}
#endif

uint8_t el_port_mb_rtu_open(uint8_t uart, uint32_t baud, uint8_t parity, uint8_t unit)
{
    (void)uart;
    (void)baud;
    (void)parity;
    (void)unit;
    return EL_MB_PORT_OFF;
}

int16_t el_port_mb_rtu_getc(void)
{
    return EL_MB_NONE;
}

void el_port_mb_rtu_send(const uint8_t *adu, uint16_t len)
{
    (void)adu;
    (void)len;
}

int main(void)
{
    el_run(0, (char **)0);
    el_port_shutdown();
    return 0;
}
