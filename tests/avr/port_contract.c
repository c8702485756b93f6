/* The port contract (runtime_c/el_port.h): checks that every board's port
 * must pass, run on the host board (a process) and on the AVR board (in
 * simavr). It replaces the runtime's dispatcher (el_run, el_idle,
 * el_now_tick) and drives the port directly; the board's main() calls it.
 *
 * One line per check on the board's output (host: stdout; AVR: USART0,
 * polled): "ok NAME" or "FAIL NAME: detail", then "done N failed".
 *
 * Checks:
 *   init          el_port_init returns true
 *   tick_period   consecutive ticks are el_tick_us apart in real time
 *                 (AVR: within 32 CPU cycles, measured on Timer1; host:
 *                 20 ticks take 20 tick periods within 25 %)
 *   real_tick     el_port_real_tick is the tick just waited for
 *   late_tick     a tick already past returns at once (not skipped)
 *   irq_nesting   save returns the previous state; nested sections restore
 *                 the state they found (AVR: SREG's I bit is clear inside,
 *                 set again after the outer restore)
 *   irq_masks     (AVR) a critical section holds the tick interrupt off;
 *                 the tick it missed comes when it ends
 *   idle          el_port_idle(ms) serves the interfaces (el_idle) and
 *                 returns after about ms
 *   resync        after a halt, the next tick is one tick away again
 *   nv            el_port_nv_write/read round-trip at both ends of the
 *                 store; out of range is refused
 *   instants      el_port_inputs / el_port_instant can be called
 */
#include "el_types.h"
#include "el_model.h"
#include "el_port.h"
#include "el_board.h"

#if defined(EL_BOARD_HOST)
#include <stdio.h>
#include <time.h>
#define NV_SIZE EL_HOST_NV_SIZE
#else
#include <avr/io.h>
#include "avr_internal.h"
#define NV_SIZE EL_AVR_NV_SIZE
#endif

#define TICK_US 1000u

/* ---- the tables a port may look at ---- */

static uint16_t result_var;
const char el_model_name[] = "port_contract";
const uint32_t el_program_id = 0x0c0de001UL;
const uint32_t el_tick_us = TICK_US;
const uint32_t el_hyperperiod_ticks = 1u;
const el_item_t el_items[1] = {{"failures", &result_var, EL_T_U16, EL_K_VAR, EL_NO_DEVICE, 1u}};
const uint16_t el_item_count = 1u;
const el_device_t el_devices[1] = {{"", ""}};
const uint8_t el_device_count = 0u;
const el_chart_t el_charts[1] = {{"", 0u, (const char *const *)0, (const uint8_t *)0}};
const uint8_t el_chart_count = 0u;
uint16_t el_overruns[1];
const uint8_t el_task_count = 0u;
const char *const el_task_names[1] = {""};

/* ---- what the dispatcher provides ---- */

static uint64_t now_tick;
static uint32_t idle_calls;

uint64_t el_now_tick(void);
uint64_t el_now_tick(void)
{
    return now_tick;
}

void el_idle(void);
void el_idle(void)
{
    idle_calls++;
}

/* ---- board-specific: output, a fine clock ---- */

#if defined(EL_BOARD_HOST)
static void out_str(const char *s)
{
    fputs(s, stdout);
}

static void out_flush(void)
{
    fflush(stdout);
}

/* Nanoseconds. */
static uint64_t clock_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000000u + (uint64_t)ts.tv_nsec;
}
#define CLOCK_PER_TICK ((uint64_t)TICK_US * 1000u)
#else
static void out_char(char c)
{
    while ((UCSR0A & _BV(UDRE0)) == 0u) {
    }
    UDR0 = (uint8_t)c;
}

static void out_str(const char *s)
{
    while (*s != '\0') {
        out_char(*s++);
    }
}

static void out_flush(void)
{
    while ((UCSR0A & _BV(TXC0)) == 0u && (UCSR0B & _BV(TXEN0)) != 0u) {
    }
}

/* CPU cycles on Timer1 (free running at F_CPU, 16 bits, wrapping): callers
 * measure spans shorter than 4 ms. */
static uint16_t clock_now(void)
{
    uint8_t sreg = SREG;
    uint16_t t;
    cli();
    t = TCNT1;
    SREG = sreg;
    return t;
}
#define CLOCK_PER_TICK ((uint16_t)(TICK_US * (F_CPU / 1000000UL)))
#endif

static void out_u32(uint32_t v)
{
    char buf[11];
    uint8_t n = 0;
    do {
        buf[n++] = (char)('0' + v % 10u);
        v /= 10u;
    } while (v != 0u);
    while (n > 0u) {
        char c[2] = {buf[--n], '\0'};
        out_str(c);
    }
}

static uint16_t failures;

static void check(bool ok, const char *name, const char *detail, uint32_t value)
{
    if (ok) {
        out_str("ok ");
        out_str(name);
    } else {
        failures++;
        out_str("FAIL ");
        out_str(name);
        out_str(": ");
        out_str(detail);
        out_str(" ");
        out_u32(value);
    }
    out_str("\n");
}

static void wait_real_ticks(uint32_t n)
{
    /* Busy: real time passes without the port's help. */
    uint32_t start = el_port_real_tick();
#if defined(EL_BOARD_HOST)
    uint64_t until = clock_now() + (uint64_t)n * CLOCK_PER_TICK;
    (void)start;
    while (clock_now() < until) {
    }
#else
    while (el_port_real_tick() - start < n) {
    }
#endif
}

static void run_checks(void)
{
    uint32_t t;
    uint32_t worst = 0u;
    bool ok;

    /* tick_period */
    {
#if defined(EL_BOARD_HOST)
        uint64_t start, span;
        (void)el_port_wait_tick(0u);
        start = clock_now();
        for (t = 1u; t <= 20u; t++) {
            (void)el_port_wait_tick(t);
        }
        span = clock_now() - start;
        worst = (uint32_t)(span / 1000u);
        ok = span >= 20u * CLOCK_PER_TICK * 3u / 4u && span <= 20u * CLOCK_PER_TICK * 5u / 4u;
        check(ok, "tick_period", "20 ticks took (us)", worst);
#else
        uint16_t prev, now_c;
        (void)el_port_wait_tick(0u);
        (void)el_port_wait_tick(1u);
        prev = clock_now();
        for (t = 2u; t <= 20u; t++) {
            uint16_t d;
            (void)el_port_wait_tick(t);
            now_c = clock_now();
            d = (uint16_t)(now_c - prev);
            prev = now_c;
            d = d > CLOCK_PER_TICK ? (uint16_t)(d - CLOCK_PER_TICK) : (uint16_t)(CLOCK_PER_TICK - d);
            if (d > worst) {
                worst = d;
            }
        }
        check(worst <= 32u, "tick_period", "worst deviation from el_tick_us (cycles)", worst);
#endif
    }

    /* real_tick */
    (void)el_port_wait_tick(21u);
    t = el_port_real_tick();
    check(t == 21u || t == 22u, "real_tick", "after waiting for tick 21, real tick", t);

    /* late_tick */
    wait_real_ticks(3u);
    {
#if defined(EL_BOARD_HOST)
        uint64_t start = clock_now();
        (void)el_port_wait_tick(22u);
        check(clock_now() - start < CLOCK_PER_TICK / 2u, "late_tick", "a past tick waited (ns)",
              (uint32_t)(clock_now() - start));
#else
        uint16_t start = clock_now();
        uint16_t d;
        (void)el_port_wait_tick(22u);
        d = (uint16_t)(clock_now() - start);
        check(d < CLOCK_PER_TICK / 2u, "late_tick", "a past tick waited (cycles)", d);
#endif
    }

    /* irq_nesting */
    {
        el_irq_state_t s0, s1, s2, s3;
        bool inside_masked = true, after_on = true;
        s0 = el_port_irq_save();
        s1 = el_port_irq_save();
#if defined(EL_BOARD_AVR)
        inside_masked = (SREG & _BV(SREG_I)) == 0u;
#endif
        el_port_irq_restore(s1);
        s2 = el_port_irq_save();
        el_port_irq_restore(s2);
#if defined(EL_BOARD_AVR)
        inside_masked = inside_masked && (SREG & _BV(SREG_I)) == 0u;
#endif
        el_port_irq_restore(s0);
#if defined(EL_BOARD_AVR)
        after_on = (SREG & _BV(SREG_I)) != 0u;
#endif
        s3 = el_port_irq_save();
        el_port_irq_restore(s3);
        ok = s0 != s1 && s2 == s1 && s3 == s0 && inside_masked && after_on;
        check(ok, "irq_nesting", "states (s0 s1 s2 s3 as bits)",
              (uint32_t)s0 << 24 | (uint32_t)s1 << 16 | (uint32_t)s2 << 8 | s3);
    }

    /* irq_masks */
#if defined(EL_BOARD_AVR)
    {
        el_irq_state_t s;
        uint32_t before, during, after;
        uint8_t k;
        (void)el_port_wait_tick(23u);
        s = el_port_irq_save();
        before = el_port_real_tick();
        for (k = 0u; k < 3u; k++) { /* three tick periods with interrupts masked */
            uint16_t start = clock_now();
            while ((uint16_t)(clock_now() - start) < CLOCK_PER_TICK) {
            }
        }
        during = el_port_real_tick();
        el_port_irq_restore(s);
        after = el_port_real_tick();
        check(during == before && after == before + 1u, "irq_masks",
              "real tick before/during/after (x 65536^n)", before << 16 | during << 8 | after);
    }
#else
    check(true, "irq_masks", "", 0u); /* the host port has no interrupts to mask */
#endif

    /* idle */
    {
        uint32_t calls = idle_calls;
        uint32_t r0 = el_port_real_tick();
        el_port_idle(5u);
        t = el_port_real_tick() - r0;
        check(idle_calls > calls && t >= 4u && t <= 8u, "idle", "ticks in el_port_idle(5 ms)", t);
    }

    /* resync: a halt of about 10 ticks at logical tick 40 */
    {
        uint32_t r;
        (void)el_port_wait_tick(40u);
        now_tick = 40u;
        el_port_idle(10u);
        el_port_resync();
        r = el_port_real_tick();
#if defined(EL_BOARD_HOST)
        {
            uint64_t start = clock_now(), d;
            (void)el_port_wait_tick(41u);
            d = clock_now() - start;
            check(r == 40u && d >= CLOCK_PER_TICK / 2u && d <= CLOCK_PER_TICK * 3u, "resync",
                  "real tick after resync / wait for the next (us)", r * 1000000u + (uint32_t)(d / 1000u));
        }
#else
        {
            uint16_t start = clock_now(), d;
            (void)el_port_wait_tick(41u);
            d = (uint16_t)(clock_now() - start);
            check(r == 40u && d >= CLOCK_PER_TICK / 2u, "resync", "real tick after resync / wait (cycles)",
                  r * 100000u + d);
        }
#endif
    }

    /* nv */
    {
        uint8_t w[8], rd[8];
        uint8_t i;
        bool good = true;
        for (i = 0u; i < 8u; i++) {
            w[i] = (uint8_t)(0xA0u + i * 7u);
        }
        good = good && el_port_nv_write(0u, w, 8u) && el_port_nv_read(0u, rd, 8u);
        for (i = 0u; i < 8u; i++) {
            good = good && rd[i] == w[i];
            w[i] = (uint8_t)~w[i];
        }
        good = good && el_port_nv_write((uint16_t)(NV_SIZE - 8u), w, 8u) &&
               el_port_nv_read((uint16_t)(NV_SIZE - 8u), rd, 8u);
        for (i = 0u; i < 8u; i++) {
            good = good && rd[i] == w[i];
        }
        good = good && !el_port_nv_write((uint16_t)(NV_SIZE - 4u), w, 8u);
        good = good && !el_port_nv_read((uint16_t)(NV_SIZE - 4u), rd, 8u);
        good = good && el_port_nv_write(0u, w, 0u) && el_port_nv_read((uint16_t)NV_SIZE, rd, 0u);
        check(good, "nv", "size", NV_SIZE);
    }

    /* instants */
    el_port_inputs(42u);
    el_port_instant(42u);
    check(true, "instants", "", 0u);
}

void el_run(int argc, char **argv)
{
#if defined(EL_BOARD_AVR)
    /* Timer1 free running at F_CPU, our fine clock. */
    TCCR1A = 0u;
    TCCR1B = _BV(CS10);
    /* USART0 for the report, 115200 8N1 (the board's UART code is not used). */
    UCSR0A = _BV(U2X0);
    UCSR0C = (uint8_t)(_BV(UCSZ01) | _BV(UCSZ00));
    UBRR0H = 0u;
    UBRR0L = 16u;
    UCSR0B = _BV(TXEN0);
#endif
    if (!el_port_init(argc, argv)) {
        out_str("FAIL init: el_port_init returned false\n");
        out_flush();
        return;
    }
    check(true, "init", "", 0u);
    run_checks();
    result_var = failures;
    out_str("done ");
    out_u32(failures);
    out_str(" failed\n");
    out_flush();
    el_port_shutdown();
}
