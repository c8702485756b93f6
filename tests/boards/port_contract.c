/* The port contract (runtime_c/el_port.h): checks that every board's port
 * must pass, built and run by the board itself (Board.run_port_program:
 * a process on the host, the MCU in its simulator). It replaces the
 * runtime's dispatcher (el_run, el_idle, el_now_tick) and drives the port
 * directly; the board's main() calls it.
 *
 * What differs between boards is in the board's port_contract_hooks.h
 * (docs/boards.md, "Adding a board"): where the report goes, a fine clock,
 * the interrupt state.
 *
 * One line per check on the board's console: "ok NAME" or
 * "FAIL NAME: detail", then "done N failed".
 *
 * Checks:
 *   init          el_port_init returns true
 *   tick_period   consecutive ticks are el_tick_us apart in real time
 *                 (exact boards: each one within PC_TICK_TOLERANCE fine-clock
 *                 periods; others: 20 ticks take 20 tick periods within 25 %)
 *   real_tick     el_port_real_tick is the tick just waited for
 *   late_tick     a tick already past returns at once (not skipped)
 *   irq_nesting   save returns the previous state; nested sections restore
 *                 the state they found (with interrupts: they are off
 *                 inside, on again after the outer restore)
 *   irq_masks     (with interrupts) a critical section holds the tick
 *                 interrupt off; the tick it missed comes when it ends
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
#include "el_service.h"
#include "el_board.h"
#include "port_contract_hooks.h"

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
const uint8_t el_svc_modbus_links = 0u; /* no Modbus interface to serve */

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

/* ---- the report ---- */

static void out_u32(uint32_t v)
{
    char buf[11];
    uint8_t n = 0;
    do {
        buf[n++] = (char)('0' + v % 10u);
        v /= 10u;
    } while (v != 0u);
    while (n > 0u) {
        char c[2];
        c[0] = buf[--n];
        c[1] = '\0';
        pc_out_str(c);
    }
}

static uint16_t failures;

static void check(bool ok, const char *name, const char *detail, uint32_t value)
{
    if (ok) {
        pc_out_str("ok ");
        pc_out_str(name);
    } else {
        failures++;
        pc_out_str("FAIL ");
        pc_out_str(name);
        pc_out_str(": ");
        pc_out_str(detail);
        pc_out_str(" ");
        out_u32(value);
    }
    pc_out_str("\n");
}

/* Fine-clock periods since `start` (wrapping clocks wrap here too). */
static pc_clock_t since(pc_clock_t start)
{
    return (pc_clock_t)(pc_clock_now() - start);
}

static void wait_real_ticks(uint32_t n)
{
    /* Busy: real time passes without the port's help. */
    uint32_t start = el_port_real_tick();
    while (el_port_real_tick() - start < n) {
    }
}

static void check_tick_period(void)
{
    uint32_t t;
#if PC_EXACT_TICKS
    pc_clock_t prev, worst = 0u;
    (void)el_port_wait_tick(0u);
    (void)el_port_wait_tick(1u);
    prev = pc_clock_now();
    for (t = 2u; t <= 20u; t++) {
        pc_clock_t now_c, d;
        (void)el_port_wait_tick(t);
        now_c = pc_clock_now();
        d = (pc_clock_t)(now_c - prev);
        prev = now_c;
        d = d > PC_CLOCK_PER_TICK ? (pc_clock_t)(d - PC_CLOCK_PER_TICK) : (pc_clock_t)(PC_CLOCK_PER_TICK - d);
        if (d > worst) {
            worst = d;
        }
    }
    check(worst <= PC_TICK_TOLERANCE, "tick_period", "worst deviation from el_tick_us (fine clock)",
          (uint32_t)worst);
#else
    pc_clock_t start, span;
    (void)el_port_wait_tick(0u);
    start = pc_clock_now();
    for (t = 1u; t <= 20u; t++) {
        (void)el_port_wait_tick(t);
    }
    span = since(start);
    check(span >= 20u * PC_CLOCK_PER_TICK * 3u / 4u && span <= 20u * PC_CLOCK_PER_TICK * 5u / 4u, "tick_period",
          "20 ticks took (fine clock / 1000)", (uint32_t)(span / 1000u));
#endif
}

static void check_irq_nesting(void)
{
    el_irq_state_t s0, s1, s2, s3;
    bool inside_masked = true, after_on = true;
    s0 = el_port_irq_save();
    s1 = el_port_irq_save();
    inside_masked = pc_irq_enabled() != 1;
    el_port_irq_restore(s1);
    s2 = el_port_irq_save();
    el_port_irq_restore(s2);
    inside_masked = inside_masked && pc_irq_enabled() != 1;
    el_port_irq_restore(s0);
    after_on = pc_irq_enabled() != 0;
    s3 = el_port_irq_save();
    el_port_irq_restore(s3);
    check(s0 != s1 && s2 == s1 && s3 == s0 && inside_masked && after_on, "irq_nesting",
          "states (s0 s1 s2 s3 as bits)", (uint32_t)s0 << 24 | (uint32_t)s1 << 16 | (uint32_t)s2 << 8 | s3);
}

static void check_irq_masks(void)
{
#if PC_HAS_INTERRUPTS
    el_irq_state_t s;
    uint32_t before, during, after;
    uint8_t k;
    (void)el_port_wait_tick(23u);
    s = el_port_irq_save();
    before = el_port_real_tick();
    for (k = 0u; k < 3u; k++) { /* three tick periods with interrupts masked */
        pc_clock_t start = pc_clock_now();
        while (since(start) < PC_CLOCK_PER_TICK) {
        }
    }
    during = el_port_real_tick();
    el_port_irq_restore(s);
    after = el_port_real_tick();
    check(during == before && after == before + 1u, "irq_masks", "real tick before/during/after (x 65536^n)",
          before << 16 | during << 8 | after);
#else
    check(true, "irq_masks", "", 0u); /* no interrupts to mask */
#endif
}

static void check_nv(void)
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
    good = good && el_port_nv_write((uint16_t)(PC_NV_SIZE - 8u), w, 8u) &&
           el_port_nv_read((uint16_t)(PC_NV_SIZE - 8u), rd, 8u);
    for (i = 0u; i < 8u; i++) {
        good = good && rd[i] == w[i];
    }
    good = good && !el_port_nv_write((uint16_t)(PC_NV_SIZE - 4u), w, 8u);
    good = good && !el_port_nv_read((uint16_t)(PC_NV_SIZE - 4u), rd, 8u);
    good = good && el_port_nv_write(0u, w, 0u) && el_port_nv_read((uint16_t)PC_NV_SIZE, rd, 0u);
    check(good, "nv", "size", PC_NV_SIZE);
}

static void run_checks(void)
{
    uint32_t t;

    check_tick_period();

    (void)el_port_wait_tick(21u);
    t = el_port_real_tick();
    check(t == 21u || t == 22u, "real_tick", "after waiting for tick 21, real tick", t);

    wait_real_ticks(3u);
    {
        pc_clock_t start = pc_clock_now(), d;
        (void)el_port_wait_tick(22u);
        d = since(start);
        check(d < PC_CLOCK_PER_TICK / 2u, "late_tick", "a past tick waited (fine clock)", (uint32_t)d);
    }

    check_irq_nesting();
    check_irq_masks();

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
        pc_clock_t start, d;
        (void)el_port_wait_tick(40u);
        now_tick = 40u;
        el_port_idle(10u);
        el_port_resync();
        r = el_port_real_tick();
        start = pc_clock_now();
        (void)el_port_wait_tick(41u);
        d = since(start);
        check(r == 40u && d >= PC_CLOCK_PER_TICK / 2u && (PC_EXACT_TICKS || d <= PC_CLOCK_PER_TICK * 3u), "resync",
              "real tick after resync x 100000 + the wait for the next (fine clock)", r * 100000u + (uint32_t)d);
    }

    check_nv();

    el_port_inputs(42u);
    el_port_instant(42u);
    check(true, "instants", "", 0u);
}

void el_run(int argc, char **argv)
{
    pc_console_init();
    if (!el_port_init(argc, argv)) {
        pc_out_str("FAIL init: el_port_init returned false\n");
        pc_out_flush();
        return;
    }
    check(true, "init", "", 0u);
    run_checks();
    result_var = failures;
    pc_out_str("done ");
    out_u32(failures);
    pc_out_str(" failed\n");
    pc_out_flush();
    el_port_shutdown();
}
