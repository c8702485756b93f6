/* EasyLab AVR board: the port interface of runtime_c/el_port.h.
 *
 * Time: Timer2 in CTC mode interrupts every EL_AVR_TICK_OCR + 1 periods of
 * F_CPU / EL_AVR_TICK_PRESCALE; every EL_AVR_TICK_ISRS interrupts make one
 * LET tick of el_tick_us (the generator chose the three so that their
 * product is the tick exactly whenever it can: docs/boards.md, "Tick and
 * drift"). Tick n is due n ticks after el_port_init. el_port_wait_tick
 * serves the interfaces (el_idle) and sleeps (idle mode: timers and UARTs
 * run) until the tick has come; a late tick returns at once (lateness is
 * counted by the dispatcher, never skipped).
 *
 * Critical sections save SREG and clear its I bit; restoring SREG restores
 * I as it was, so they nest.
 *
 * The watchdog runs from el_port_init on (EL_AVR_WDTO) and is reset while
 * waiting: a task body that keeps the CPU longer resets the MCU.
 *
 * Simulation builds (EL_AVR_SIM, `easylab build --sim`) tell the simavr
 * harness (sim/) about instants through GPIOR0: el_port_inputs writes
 * EL_AVR_SIM_INPUTS after storing the tick in el_avr_sim_tick and waits
 * while the harness keeps GPIOR1 nonzero (it is delivering input: UART
 * frames, encoder pulses); el_port_instant writes EL_AVR_SIM_INSTANT. The
 * harness reads the items from RAM at that moment. Other builds do nothing
 * there.
 */
#include "avr_internal.h"
#include "el_port.h"
#include "el_dispatch.h"

#include <avr/sleep.h>
#include <avr/wdt.h>

#if defined(EL_DEBUG) && EL_DEBUG && !(defined(EL_RELEASE) && EL_RELEASE)
#include "el_debug.h" /* EL_DEBUG_SERVER: whether to open the debug UART */
#endif

/* ---- simavr's .mmcu section: `simavr FILE.elf` finds the MCU and clock.
 * The layout of simavr's avr_mcu_section.h (tags 1 and 2); stripped from
 * the .hex (objcopy -R .mmcu). */
struct el_avr_mmcu_string {
    uint8_t tag;
    uint8_t len;
    char text[64];
} __attribute__((__packed__));
struct el_avr_mmcu_long {
    uint8_t tag;
    uint8_t len;
    uint32_t value;
} __attribute__((__packed__));

const struct el_avr_mmcu_string el_avr_mmcu_name __attribute__((section(".mmcu"), used)) = {
    1u, 64u, EL_AVR_MCU_NAME};
const struct el_avr_mmcu_long el_avr_mmcu_freq __attribute__((section(".mmcu"), used)) = {
    2u, 4u, F_CPU};

/* ---- reset: the watchdog survives a reset, so stop it before anything ---- */

/* MCUSR at reset (EXTRF, PORF, BORF, WDRF): why the MCU started. */
uint8_t el_avr_reset_cause __attribute__((section(".noinit")));
/* A debugger RESET with RESET_HALT (avr_interfaces.c) leaves 0x5A here,
 * kept across the watchdog reset; el_port_init reads and clears it. */
uint8_t el_avr_reset_halt __attribute__((section(".noinit")));
/* GPIOR2 at boot of a simulation build: the harness's --halt (halt at the
 * first instant, as the host board's `--debug ...,halt`). */
#define EL_AVR_SIM_HALT 0xA5u

void el_avr_early_init(void) __attribute__((naked, used, section(".init3")));
void el_avr_early_init(void)
{
    el_avr_reset_cause = MCUSR;
    MCUSR = 0u;
    wdt_disable();
}

/* ---- time ---- */

static volatile el_wtick_t ticks;    /* LET ticks since el_port_init (el_types.h: 16 or 32 bits) */
static volatile uint32_t isr_count;  /* Timer2 interrupts since el_port_init */
#if EL_AVR_TICK_ISRS > 1
static volatile uint16_t isr_left = EL_AVR_TICK_ISRS; /* interrupts left in this tick */
#endif

ISR(TIMER2_COMPA_vect)
{
    isr_count++;
#if defined(EL_AVR_I2C) && EL_AVR_I2C
    el_avr_twi_poll(); /* a job waiting for a busy chip on the I2C bus */
#endif
#if EL_AVR_TICK_ISRS > 1
    if (--isr_left == 0u) {
        isr_left = EL_AVR_TICK_ISRS;
        ticks++;
    }
#else
    ticks++;
#endif
}

uint32_t el_avr_clock(void)
{
    uint8_t sreg = SREG;
    uint32_t n;
    uint8_t t;
    cli();
    n = isr_count;
    t = TCNT2;
    if ((TIFR2 & _BV(OCF2A)) != 0u) { /* a compare match not yet served */
        n++;
        t = TCNT2;
    }
    SREG = sreg;
    return n * (uint32_t)(EL_AVR_TICK_OCR + 1u) + t;
}

uint32_t el_avr_clock_from_us(uint32_t us)
{
    /* EL_AVR_CLOCK_KHZ: fine-clock periods per ms, rounded up (32-bit
     * arithmetic only: no 64-bit division code on the MCU). */
    return (us / 1000u) * (uint32_t)EL_AVR_CLOCK_KHZ + ((us % 1000u) * (uint32_t)EL_AVR_CLOCK_KHZ + 999u) / 1000u;
}

static el_wtick_t read_ticks(void)
{
    uint8_t sreg = SREG;
    el_wtick_t t;
    cli();
    t = ticks;
    SREG = sreg;
    return t;
}

static void start_tick_timer(void)
{
    TCCR2B = 0u;
    TCCR2A = _BV(WGM21); /* CTC, TOP = OCR2A */
    TCNT2 = 0u;
    OCR2A = EL_AVR_TICK_OCR;
    TIFR2 = _BV(OCF2A);
    TIMSK2 = _BV(OCIE2A);
    TCCR2B = EL_AVR_TICK_CS;
}

bool el_port_init(int argc, char **argv)
{
    (void)argc;
    (void)argv;
#if defined(JTD)
    /* PF4..PF7 (ADC4..7) are JTAG pins unless JTAG is off: a timed sequence. */
    MCUCR |= _BV(JTD);
    MCUCR |= _BV(JTD);
#endif
    /* External interrupts sense edges, not a low level, while masked:
     * simavr 1.6 polls a low-level pin every cycle even then (a PWM output
     * or a low input on an INTn pin would slow a simulation 50 times). */
    EICRA = 0x55u;
#if defined(EICRB)
    EICRB = 0x55u;
#endif
#if defined(EL_AVR_DEBUG_UART) && defined(EL_DEBUG_SERVER) && EL_DEBUG_SERVER
    el_avr_uart_open(EL_AVR_DEBUG_UART, EL_AVR_DEBUG_BAUD, EL_AVR_PARITY_NONE);
    /* Halt at the first instant after a RESET with RESET_HALT only (a
     * power-on leaves .noinit undefined: the reset cause must be the watchdog). */
    if (el_avr_reset_halt == 0x5Au && (el_avr_reset_cause & _BV(WDRF)) != 0u) {
        el_debug_halt_at_start();
    }
#if defined(EL_AVR_SIM) && EL_AVR_SIM
    if (GPIOR2 == EL_AVR_SIM_HALT) { /* the harness's --halt */
        el_debug_halt_at_start();
    }
    GPIOR2 = 0u;
#endif
#endif
#if defined(EL_AVR_REMOTE_UART)
    /* A remote-execution proxy's link (avr_remote.c). */
    el_avr_uart_open(EL_AVR_REMOTE_UART, EL_REMOTE_BAUD, EL_AVR_PARITY_NONE);
#endif
    el_avr_reset_halt = 0u;
    /* ticks and isr_count are zero from boot (.bss): el_port_init runs once. */
    start_tick_timer();
    wdt_enable(EL_AVR_WDTO);
    sei();
    return true;
}

bool el_port_wait_tick(el_wtick_t tick)
{
#if defined(EL_ROUND_SLAVE)
    {
        for (;;) {
            wdt_reset();
            el_idle(); /* the bus: the sync that lets the tick run */
            cli();
            if (el_round_gate(tick) != 0) {
                sei();
                return true;
            }
            set_sleep_mode(SLEEP_MODE_IDLE); /* until a byte or the timer */
            sleep_enable();
            sei();
            sleep_cpu();
            sleep_disable();
        }
    }
#endif
    for (;;) {
        wdt_reset();
        if (EL_TICK_REACHED(read_ticks(), tick)) {
            return true;
        }
        el_idle();
        cli();
        if (EL_TICK_REACHED(ticks, tick)) {
            sei();
            return true;
        }
        /* SEI takes effect after the next instruction: no interrupt can
         * come between the test and SLEEP unseen. */
        set_sleep_mode(SLEEP_MODE_IDLE);
        sleep_enable();
        sei();
        sleep_cpu();
        sleep_disable();
    }
}

/* Timer2 interrupts in 256 ms (a constant of the build). */
#define ISRS_PER_256_MS \
    ((uint32_t)(F_CPU / 1000UL * 256UL / ((uint32_t)EL_AVR_TICK_PRESCALE * ((uint32_t)EL_AVR_TICK_OCR + 1UL))))

void el_port_idle(uint16_t max_ms)
{
    /* Timer2 interrupts rather than the fine clock: a product by a constant
     * and a shift, rounded down (never longer than max_ms). Their count's
     * low byte is read alone: one load, atomic. */
    uint16_t left = (uint16_t)(((uint32_t)max_ms * ISRS_PER_256_MS) >> 8);
    uint8_t seen = *(volatile uint8_t *)&isr_count;
    for (;;) {
        uint8_t now, passed;
        wdt_reset();
        el_idle();
        if (left == 0u) {
            return;
        }
        set_sleep_mode(SLEEP_MODE_IDLE);
        sleep_enable();
        sleep_cpu(); /* the next interrupt: a timer period at most */
        sleep_disable();
        now = *(volatile uint8_t *)&isr_count;
        passed = (uint8_t)(now - seen);
        seen = now;
        left = passed >= left ? 0u : (uint16_t)(left - passed);
    }
}

void el_port_resync(void)
{
    uint8_t sreg = SREG;
    cli();
    /* The current tick is due now: a fresh tick period starts. */
    ticks = (el_wtick_t)el_now_tick();
#if EL_AVR_TICK_ISRS > 1
    isr_left = EL_AVR_TICK_ISRS;
#endif
    TCNT2 = 0u;
    TIFR2 = _BV(OCF2A);
    SREG = sreg;
}

el_wtick_t el_port_real_tick(void)
{
    return read_ticks();
}

/* ---- critical sections ---- */

el_irq_state_t el_port_irq_save(void)
{
    el_irq_state_t state = SREG;
    cli();
    return state;
}

void el_port_irq_restore(el_irq_state_t state)
{
    SREG = state;
}

/* ---- instants ---- */

#if defined(EL_AVR_SIM) && EL_AVR_SIM
/* The instant being processed, for the harness (read from RAM; 16 or 32
 * bits, el_tick_t, which the harness extends by the symbol's size). */
volatile el_tick_t el_avr_sim_tick;
#endif

void el_port_inputs(el_tick_t tick)
{
#if defined(EL_AVR_SIM) && EL_AVR_SIM
    el_avr_sim_tick = tick;
    GPIOR1 = 0u;
    GPIOR0 = EL_AVR_SIM_INPUTS;
    while (GPIOR1 != 0u) { /* the harness is delivering input (interrupts on) */
        wdt_reset();
    }
#else
    (void)tick;
#endif
}

void el_port_instant(el_tick_t tick)
{
#if defined(EL_AVR_SIM) && EL_AVR_SIM
    el_avr_sim_tick = tick;
    GPIOR0 = EL_AVR_SIM_INSTANT;
#else
    (void)tick;
#endif
}

void el_port_shutdown(void)
{
    /* An MCU run never ends; stop for good (simavr ends a run that
     * sleeps with interrupts off). */
    wdt_disable();
    cli();
    set_sleep_mode(SLEEP_MODE_PWR_DOWN);
    sleep_enable();
    for (;;) {
        sleep_cpu();
    }
}

/* ---- the ADC ---- */

void el_avr_adc_open(uint8_t ch)
{
    ADCSRA = _BV(ADEN) | _BV(ADPS2) | _BV(ADPS1) | _BV(ADPS0); /* 125 kHz */
    if (ch < 6u) {
        DIDR0 |= (uint8_t)_BV(ch);
    }
#if defined(DIDR2)
    else if (ch >= 8u) {
        DIDR2 |= (uint8_t)_BV(ch - 8u);
    } else {
        DIDR0 |= (uint8_t)_BV(ch);
    }
#endif
}

uint16_t el_avr_adc_read(uint8_t ch)
{
#if defined(MUX5)
    if (ch >= 8u) {
        ADCSRB |= _BV(MUX5);
    } else {
        ADCSRB &= (uint8_t)~_BV(MUX5);
    }
#endif
    ADMUX = (uint8_t)(_BV(REFS0) | (ch & 7u)); /* AVCC reference, right adjusted */
    ADCSRA |= _BV(ADSC);
    while ((ADCSRA & _BV(ADSC)) != 0u) {
    }
    return ADC;
}

/* ---- the program (test and benchmark programs bring their own: EL_AVR_NO_MAIN) ---- */

#if !defined(EL_AVR_NO_MAIN)
int main(void)
{
    /* Nothing kept across el_run: it saves no registers (OS_task, board.toml). */
    el_run(0, (char **)0);
    el_port_shutdown();
    return 0;
}
#endif
