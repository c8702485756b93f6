/* EasyLab AVR board: the simavr harness (docs/boards.md, "Simulation").
 *
 * Runs a firmware built with `easylab build --board avr --sim` in simavr
 * (Debian's libsimavr) with the host board's command line where it makes
 * sense, so that one stimulus gives one trace on both boards:
 *
 *   NAME-sim [--fast] [--duration T] [--cycles N] [--stimulus S.csv]
 *            [--trace T.csv|T.vcd] [--pins P.csv|P.vcd] [--nvram FILE]
 *            [--chips DIR] [--uartN pty:LINK|tcp:PORT|file:PATH|null] [--wait]
 *            [--elf FILE] [--report] [--help]
 *
 * Instants: the simulation build's el_port_inputs and el_port_instant write
 * a marker to GPIOR0, which this harness hooks. At the inputs marker of an
 * instant (after the outputs due then were published, before devices are
 * read) it applies the stimulus due by then, exactly as the host board does:
 * params and vars are written into the MCU's RAM, device `out` data are put
 * on the hardware the build maps them to (an ADC channel's voltage, an input
 * pin's level, line camera frames on a UART, quadrature edges on encoder
 * pins, the temperature of a sensor on the I2C bus: sim_chips.c), and the
 * firmware's own drivers read them. While UART frames or
 * encoder edges are still on their way it keeps GPIOR1 nonzero, and the
 * firmware waits. At the instant marker it copies every item and chart
 * from the MCU's RAM and records them with the host board's trace code
 * (host_trace.c), so the CSV and VCD files are the host board's, byte for
 * byte. --duration T ends the run at the first instant whose time is >= T,
 * which is not recorded (the host board's rule).
 *
 * Time: simavr counts CPU cycles exactly. --fast runs flat out (the CPU's
 * sleep skips to the next event at once); otherwise the harness keeps the
 * simulated clock in step with the wall clock. UARTs: each on a
 * pseudo-terminal (a symlink LINK to it), a TCP port on 127.0.0.1 (one
 * client at a time; port 0 picks one), a file (output only) or nothing;
 * their paths are printed on stderr. --wait holds the CPU until every pty
 * and TCP UART has a client. Exit status: 0 the run ended (duration,
 * cycles, the firmware stopped); 1 an error during the run (trace write,
 * crash, a stimulus value the hardware cannot produce); 2 a bad command
 * line or input file.
 */
#include "sim_model.h"
#include "sim_chips.h"
#include "host_internal.h"

#include "sim_avr.h"
#include "sim_elf.h"
#include "sim_core.h"
#include "sim_irq.h"
#include "avr_ioport.h"
#include "avr_uart.h"
#include "avr_adc.h"
#include "avr_eeprom.h"

#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <pty.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/socket.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

DEFINE_FIFO(uint16_t, uart_fifo); /* simavr's UART input FIFO accessors */

/* The logical time of the instant the firmware is at (sim_io.c). */
extern uint64_t el_sim_now_us;

#define EXIT_OK 0
#define EXIT_RUN 1
#define EXIT_USAGE 2

/* The simulation build's markers (boards/avr/avr_internal.h). */
#define GPIOR0_ADDR 0x3Eu
#define GPIOR1_ADDR 0x4Au
#define GPIOR2_ADDR 0x4Bu
#define MARK_INPUTS 1u
#define MARK_INSTANT 2u

/* Quadrature edges of one encoder are this many cycles apart (125 us):
 * room for the pin-change interrupts of several encoders stepping at once
 * (about 100 cycles each); closer edges would be lost as on a board. */
#define ENCODER_EDGE_CYCLES 2000u
/* How often (cycles) the harness serves the UARTs and the wall clock. */
#define SERVICE_CYCLES 1600u

static avr_t *avr;
static int exit_status = EXIT_OK;
static volatile sig_atomic_t stop_signal;
static bool stop_run;

/* ---- options ---- */

typedef enum { U_NONE, U_PTY, U_TCP, U_FILE } uart_mode_t;

typedef struct {
    char name;            /* '0'..'3' */
    uart_mode_t mode;
    const char *arg;
    int fd;               /* pty master, TCP client, file */
    int listen_fd;        /* TCP */
    int keep_fd;          /* pty: our slave descriptor */
    bool link_made;
    bool xoff;
    bool rx_enabled_seen;
    uint8_t in[4096];     /* bytes from the client for the MCU */
    size_t in_len;
    avr_uart_t *uart;
    /* Line camera frames on their way. */
    bool delivering;
} uart_t;

static struct {
    bool fast;
    bool has_duration;
    uint64_t duration_us;
    bool has_cycles;
    uint64_t cycles;
    const char *stimulus;
    const char *trace;
    const char *pins;
    const char *nvram;
    const char *chips;
    const char *elf;
    bool wait;
    bool halt;
    bool report;
} opt;

static uart_t uarts[4];

static void usage(FILE *f)
{
    fprintf(f,
            "usage: %s [--fast] [--duration T] [--cycles N] [--stimulus FILE.csv] [--trace FILE.csv|FILE.vcd]\n"
            "          [--pins FILE.csv|FILE.vcd] [--nvram FILE] [--chips DIR] [--uartN pty:LINK|tcp:PORT|file:PATH|null]\n"
            "          [--wait] [--halt] [--elf FILE] [--report] [--help]\n"
            "Runs the %s firmware of model %s in simavr.\n"
            "  --fast            flat out (default: in step with the wall clock)\n"
            "  --duration T      end at the first instant at or after T (10s, 500ms, 250us, 2m, 1h)\n"
            "  --cycles N        end after N CPU cycles\n"
            "  --stimulus FILE   device data, params and vars over time (the host board's format)\n"
            "  --trace FILE      items and charts at every instant (.csv or .vcd, the host board's format)\n"
            "  --pins FILE       the model's pins as they change (.csv: cycle,time_us,pin,value; .vcd);\n"
            "                    a PWM output as its duty 0..255\n"
            "  --nvram FILE      the EEPROM (%lu bytes), read at start and written at the end\n"
            "  --chips DIR       the memories of the EEPROMs on the I2C bus: DIR/i2cB-0xAA.bin, read at start\n"
            "                    (erased when absent) and written at the end\n"
            "  --uartN SPEC      UART N on a pseudo-terminal (symlink LINK), TCP port, file or nothing\n"
            "  --wait            hold the CPU until every pty and TCP UART has a client\n"
            "  --halt            halt at the first instant for the debugger (the host's --debug ...,halt)\n"
            "  --elf FILE        run this ELF (default: %s)\n"
            "  --report          print cycles, instants and UART errors on stderr at the end\n",
            el_host_prog, sim_mcu, el_model_name, (unsigned long)sim_nv_size, sim_elf_default);
}

/* A duration with a unit, exact to the microsecond (the host board's rules). */
static bool parse_duration(const char *text, uint64_t *us)
{
    static const struct {
        const char *unit;
        uint64_t scale;
    } units[] = {{"us", 1u}, {"ms", 1000u}, {"s", 1000000u}, {"min", 60000000u}, {"m", 60000000u},
                 {"h", 3600000000u}};
    const char *p = text;
    uint64_t whole = 0, frac = 0, frac_scale = 1;
    bool digits = false;
    size_t i;
    while (*p >= '0' && *p <= '9') {
        if (whole > UINT64_MAX / 10u)
            return false;
        whole = whole * 10u + (uint64_t)(*p++ - '0');
        digits = true;
    }
    if (*p == '.') {
        p++;
        while (*p >= '0' && *p <= '9') {
            if (frac_scale > 1000000000000u)
                return false;
            frac = frac * 10u + (uint64_t)(*p++ - '0');
            frac_scale *= 10u;
            digits = true;
        }
    }
    if (!digits)
        return false;
    if (*p == ' ')
        p++;
    for (i = 0; i < sizeof units / sizeof units[0]; i++) {
        if (strcmp(p, units[i].unit) == 0) {
            uint64_t s = units[i].scale;
            if ((frac * s) % frac_scale != 0u || whole > UINT64_MAX / s)
                return false;
            *us = whole * s + frac * s / frac_scale;
            return true;
        }
    }
    return false;
}

static bool takes_value(const char *a)
{
    static const char *const with_value[] = {"--duration", "--cycles", "--stimulus", "--trace", "--pins",
                                             "--nvram", "--chips", "--elf"};
    size_t i;
    for (i = 0; i < sizeof with_value / sizeof with_value[0]; i++)
        if (strcmp(a, with_value[i]) == 0)
            return true;
    return strncmp(a, "--uart", 6) == 0 && a[6] >= '0' && a[6] <= '3' && a[7] == '\0';
}

static int parse_args(int argc, char **argv)
{
    int i;
    for (i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (strcmp(a, "--help") == 0) {
            usage(stdout);
            return EXIT_OK + 100;
        } else if (strcmp(a, "--fast") == 0) {
            opt.fast = true;
        } else if (strcmp(a, "--wait") == 0) {
            opt.wait = true;
        } else if (strcmp(a, "--halt") == 0) {
            opt.halt = true;
        } else if (strcmp(a, "--report") == 0) {
            opt.report = true;
        } else if (!takes_value(a)) {
            el_host_error("unknown option '%s' (--help lists them)", a);
            return EXIT_USAGE;
        } else if (v == NULL) {
            el_host_error("%s: a value must follow", a);
            return EXIT_USAGE;
        } else if (strcmp(a, "--duration") == 0) {
            if (!parse_duration(v, &opt.duration_us)) {
                el_host_error("--duration %s: give a number and a unit: us, ms, s, m, h (exact to 1 us)", v);
                return EXIT_USAGE;
            }
            opt.has_duration = true;
            i++;
        } else if (strcmp(a, "--cycles") == 0) {
            char *end;
            errno = 0;
            opt.cycles = strtoull(v, &end, 10);
            if (*v == '\0' || *end != '\0' || errno != 0) {
                el_host_error("--cycles %s: give a whole number of CPU cycles", v);
                return EXIT_USAGE;
            }
            opt.has_cycles = true;
            i++;
        } else if (strcmp(a, "--stimulus") == 0) {
            opt.stimulus = v;
            i++;
        } else if (strcmp(a, "--trace") == 0) {
            opt.trace = v;
            i++;
        } else if (strcmp(a, "--pins") == 0) {
            opt.pins = v;
            i++;
        } else if (strcmp(a, "--nvram") == 0) {
            opt.nvram = v;
            i++;
        } else if (strcmp(a, "--chips") == 0) {
            opt.chips = v;
            i++;
        } else if (strcmp(a, "--elf") == 0) {
            opt.elf = v;
            i++;
        } else if (strncmp(a, "--uart", 6) == 0 && a[6] >= '0' && a[6] <= '3' && a[7] == '\0') {
            uart_t *u = &uarts[a[6] - '0'];
            if (strchr(sim_uarts, a[6]) == NULL) {
                el_host_error("%s: the %s has no UART %c (UARTs: %s)", a, sim_mcu, a[6], sim_uarts);
                return EXIT_USAGE;
            }
            if (strncmp(v, "pty:", 4) == 0 && v[4] != '\0') {
                u->mode = U_PTY;
                u->arg = v + 4;
            } else if (strncmp(v, "tcp:", 4) == 0 && v[4] != '\0') {
                u->mode = U_TCP;
                u->arg = v + 4;
            } else if (strncmp(v, "file:", 5) == 0 && v[5] != '\0') {
                u->mode = U_FILE;
                u->arg = v + 5;
            } else if (strcmp(v, "null") == 0) {
                u->mode = U_NONE;
            } else {
                el_host_error("%s %s: give pty:LINK, tcp:PORT, file:PATH or null", a, v);
                return EXIT_USAGE;
            }
            i++;
        }
    }
    return EXIT_OK;
}

/* ---- the MCU's RAM ---- */

static void ram_read(uint16_t addr, void *dst, size_t n)
{
    memcpy(dst, avr->data + addr, n);
}

static void ram_write(uint16_t addr, const void *src, size_t n)
{
    memcpy(avr->data + addr, src, n);
}

static uint64_t sim_tick(void)
{
    uint8_t b[8];
    uint64_t t = 0;
    int i;
    ram_read(sim_tick_addr, b, sizeof b);
    for (i = 7; i >= 0; i--)
        t = t << 8 | b[i];
    return t;
}

/* Copy items of these kinds (bit per EL_K_) and the charts from the MCU into
 * the mirrors. */
static void mirror_from_mcu(unsigned kinds, bool charts)
{
    uint16_t i;
    uint8_t c;
    for (i = 0; i < el_item_count; i++) {
        if ((kinds & (1u << el_items[i].kind)) != 0u && sim_item_addr[i].addr != 0xFFFFu)
            ram_read(sim_item_addr[i].addr, el_items[i].addr, sim_item_addr[i].size);
    }
    if (charts)
        for (c = 0; c < el_chart_count; c++)
            if (sim_chart_addr[c].addr != 0xFFFFu)
                ram_read(sim_chart_addr[c].addr, (void *)el_charts[c].active, sim_chart_addr[c].size);
}

/* ---- hardware behind device data ---- */

typedef struct {
    unsigned char value[8];  /* what the stimulus put on the hardware (dev_out items) */
    bool valid;
    /* encoder */
    int64_t position;        /* edges emitted so far */
    int64_t target;
    uint8_t ab;
    bool busy;
} hw_state_t;

static hw_state_t *hw_state; /* by index into sim_hw */
static unsigned busy_count;  /* deliveries on their way */
static uint64_t instants;

static avr_irq_t *pin_irq(char port, uint8_t bit)
{
    return avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ(port), bit);
}

static void set_busy(void)
{
    avr->data[GPIOR1_ADDR] = busy_count != 0u ? 1u : 0u;
}

static const uint8_t quadrature[4] = {0u, 2u, 3u, 1u}; /* A << 1 | B: A leads B going forward */

static avr_cycle_count_t encoder_edge(avr_t *a, avr_cycle_count_t when, void *param)
{
    hw_state_t *s = (hw_state_t *)param;
    const sim_hw_t *h = &sim_hw[s - hw_state];
    uint8_t ab, changed;
    (void)a;
    if (s->position == s->target) {
        s->busy = false;
        busy_count--;
        set_busy();
        return 0;
    }
    s->position += s->target > s->position ? 1 : -1;
    ab = quadrature[(uint64_t)s->position & 3u];
    changed = (uint8_t)(ab ^ s->ab);
    s->ab = ab;
    if (changed & 2u)
        avr_raise_irq(pin_irq((char)(h->a >> 8), (uint8_t)(h->a & 0xFFu)), (ab >> 1) & 1u);
    if (changed & 1u)
        avr_raise_irq(pin_irq((char)(h->b >> 8), (uint8_t)(h->b & 0xFFu)), ab & 1u);
    return when + ENCODER_EDGE_CYCLES;
}

static bool drive_hardware(uint16_t k)
{
    const sim_hw_t *h = &sim_hw[k];
    hw_state_t *s = &hw_state[k];
    const el_item_t *it = &el_items[h->item];
    switch (h->kind) {
    case SIM_HW_ADC: {
        uint16_t v;
        memcpy(&v, it->addr, sizeof v);
        if (v > 1023u) {
            el_host_error("%s = %u at %llu us: the %s's ADC gives 0..1023 (10 bits)", it->name, (unsigned)v,
                          (unsigned long long)el_sim_now_us, sim_mcu);
            return false;
        }
        /* AVCC is set to 1023 mV: one millivolt per count, exactly. */
        avr_raise_irq(avr_io_getirq(avr, AVR_IOCTL_ADC_GETIRQ, ADC_IRQ_ADC0 + h->a), v);
        return true;
    }
    case SIM_HW_PIN_IN: {
        bool level;
        memcpy(&level, it->addr, sizeof level);
        avr_raise_irq(pin_irq((char)h->a, (uint8_t)h->b), level ? 1u : 0u);
        return true;
    }
    case SIM_HW_CAMERA: {
        int16_t v;
        uint8_t frame[4];
        uart_t *u = &uarts[h->a];
        int i;
        memcpy(&v, it->addr, sizeof v);
        if (s->valid && memcmp(s->value, &v, sizeof v) == 0)
            return true;
        memcpy(s->value, &v, sizeof v);
        s->valid = true;
        frame[0] = 0xA5u;
        frame[1] = (uint8_t)((uint16_t)v & 0xFFu);
        frame[2] = (uint8_t)((uint16_t)v >> 8);
        frame[3] = (uint8_t)(frame[0] ^ frame[1] ^ frame[2]);
        if (u->uart == NULL || !avr_regbit_get(avr, u->uart->rxen))
            return true; /* the driver is not listening: the frame is lost, as on a board */
        for (i = 0; i < 4; i++)
            avr_raise_irq(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ((uint32_t)('0' + h->a)), UART_IRQ_INPUT),
                          frame[i]);
        if (!u->delivering) {
            u->delivering = true;
            busy_count++;
        }
        return true;
    }
    case SIM_HW_I2C_TEMP: {
        int32_t v = 0;
        switch (it->type) { /* a device's first `out` datum, of an integer type */
        case EL_T_I8: { int8_t x; memcpy(&x, it->addr, 1); v = x; break; }
        case EL_T_U8: { uint8_t x; memcpy(&x, it->addr, 1); v = x; break; }
        case EL_T_I16: { int16_t x; memcpy(&x, it->addr, 2); v = x; break; }
        case EL_T_U16: { uint16_t x; memcpy(&x, it->addr, 2); v = x; break; }
        case EL_T_I32: { int32_t x; memcpy(&x, it->addr, 4); v = x; break; }
        default: { uint32_t x; memcpy(&x, it->addr, 4); v = x > 0x7FFFFFFFu ? 0x7FFFFFFF : (int32_t)x; break; }
        }
        return sim_chips_temperature((uint8_t)h->a, (uint8_t)h->b, v, it->name);
    }
    case SIM_HW_ENCODER: {
        int32_t v;
        memcpy(&v, it->addr, sizeof v);
        s->target = v;
        if (s->target != s->position && !s->busy) {
            s->busy = true;
            busy_count++;
            avr_cycle_timer_register(avr, ENCODER_EDGE_CYCLES, encoder_edge, s);
        }
        return true;
    }
    default:
        return true;
    }
}

/* ---- instants ---- */

static void on_inputs(void)
{
    uint64_t tick = sim_tick();
    uint16_t i, k;
    uint8_t d;
    static unsigned char *before;
    static size_t before_size;
    size_t need = 0, off;

    el_sim_now_us = tick * (uint64_t)el_tick_us;
    if (opt.has_duration && el_sim_now_us >= opt.duration_us) {
        stop_run = true;
        return;
    }
    if (opt.stimulus == NULL)
        return;
    /* Params and vars: as the MCU has them, then the stimulus's writes. */
    mirror_from_mcu((1u << EL_K_PARAM) | (1u << EL_K_VAR), false);
    for (i = 0; i < el_item_count; i++)
        need += sim_item_addr[i].size;
    if (need > before_size) {
        free(before);
        before = malloc(need);
        before_size = need;
        if (before == NULL) {
            el_host_error("out of memory");
            exit(EXIT_RUN);
        }
    }
    for (i = 0, off = 0; i < el_item_count; i++) {
        memcpy(before + off, el_items[i].addr, sim_item_addr[i].size);
        off += sim_item_addr[i].size;
    }
    el_host_stimulus_inputs();
    for (i = 0, off = 0; i < el_item_count; i++) {
        const el_item_t *it = &el_items[i];
        if ((it->kind == EL_K_PARAM || it->kind == EL_K_VAR) && sim_item_addr[i].addr != 0xFFFFu &&
            memcmp(before + off, it->addr, sim_item_addr[i].size) != 0)
            ram_write(sim_item_addr[i].addr, it->addr, sim_item_addr[i].size);
        off += sim_item_addr[i].size;
    }
    /* Device `out` data: the hardware's state, then what the stimulus
     * puts there by now (host_stimulus.c's el_sim_read). */
    for (k = 0; k < sim_hw_count; k++) {
        const el_item_t *it = &el_items[sim_hw[k].item];
        if (it->kind == EL_K_DEV_OUT)
            memcpy(it->addr, hw_state[k].value, sim_item_addr[sim_hw[k].item].size);
    }
    for (d = 0; d < el_device_count; d++)
        el_sim_read(d);
    for (k = 0; k < sim_hw_count; k++) {
        const el_item_t *it = &el_items[sim_hw[k].item];
        if (it->kind != EL_K_DEV_OUT)
            continue;
        if (sim_hw[k].kind != SIM_HW_CAMERA)
            memcpy(hw_state[k].value, it->addr, sim_item_addr[sim_hw[k].item].size);
        if (!drive_hardware(k)) {
            exit_status = EXIT_RUN;
            stop_run = true;
            return;
        }
    }
    set_busy();
}

static void on_instant(void)
{
    uint64_t tick = sim_tick();
    el_sim_now_us = tick * (uint64_t)el_tick_us;
    instants++;
    if (opt.trace == NULL)
        return;
    mirror_from_mcu(0xFu, true);
    el_host_trace_instant(tick);
}

static void gpior0_write(struct avr_t *a, avr_io_addr_t addr, uint8_t v, void *param)
{
    (void)param;
    a->data[addr] = v;
    if (v == MARK_INPUTS)
        on_inputs();
    else if (v == MARK_INSTANT)
        on_instant();
}

/* ---- deliveries on their way ---- */

static void check_deliveries(void)
{
    int n;
    for (n = 0; n < 4; n++) {
        uart_t *u = &uarts[n];
        if (!u->delivering || u->uart == NULL)
            continue;
        if (uart_fifo_isempty(&u->uart->input) && !avr_regbit_get(avr, u->uart->rxc.raised)) {
            u->delivering = false;
            busy_count--;
            set_busy();
        }
    }
}

/* ---- pins ---- */

static FILE *pins_out;
static bool pins_vcd;
static uint64_t pins_vcd_time = UINT64_MAX;
static int16_t *pin_last; /* -1: not yet written */

/* A VCD identifier for pin k: '!' + k (at most 94 pins). */
static char pin_id(uint16_t k)
{
    return (char)('!' + k % 94u);
}

static void pin_record(uint16_t k, int value)
{
    if (pins_out == NULL || pin_last[k] == value)
        return;
    pin_last[k] = (int16_t)value;
    if (pins_vcd) {
        /* Picoseconds: a cycle is a whole number of them at 16 MHz. */
        uint64_t t = avr->cycle * (1000000000000u / sim_clock_hz);
        int b;
        if (t != pins_vcd_time) {
            fprintf(pins_out, "#%llu\n", (unsigned long long)t);
            pins_vcd_time = t;
        }
        if (sim_pins[k].kind == SIM_PIN_PWM) {
            fputc('b', pins_out);
            for (b = 7; b >= 0; b--)
                fputc((value >> b) & 1 ? '1' : '0', pins_out);
            fprintf(pins_out, " %c\n", pin_id(k));
        } else {
            fprintf(pins_out, "%d%c\n", value & 1, pin_id(k));
        }
        return;
    }
    fprintf(pins_out, "%llu,%llu,%s%s,%d\n", (unsigned long long)avr->cycle,
            (unsigned long long)(avr->cycle * 1000000u / sim_clock_hz), sim_pins[k].name,
            sim_pins[k].kind == SIM_PIN_PWM ? ".pwm" : "", value);
}

static int pwm_duty(const sim_pin_t *p)
{
    uint8_t port = avr->data[0x22u + 3u * (uint16_t)(p->port - 'A')];
    if (p->port >= 'H') /* PORTH and up live in the extended I/O space */
        port = avr->data[0x102u + 3u * (uint16_t)(p->port - 'H' - (p->port > 'I' ? 1 : 0))];
    if ((avr->data[p->tccra] >> p->com_bit) & 1u)
        return avr->data[p->ocr];
    return (port >> p->bit) & 1u ? 255 : 0;
}

static void pin_changed(struct avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq;
    pin_record((uint16_t)(uintptr_t)param, (int)(value & 1u));
}

static void pwm_reg_written(struct avr_irq_t *irq, uint32_t value, void *param)
{
    uint16_t k;
    (void)irq;
    (void)value;
    (void)param;
    for (k = 0; k < sim_pin_count; k++)
        if (sim_pins[k].kind == SIM_PIN_PWM)
            pin_record(k, pwm_duty(&sim_pins[k]));
}

static bool pins_open(void)
{
    uint16_t k;
    pin_last = calloc(sim_pin_count ? sim_pin_count : 1u, sizeof *pin_last);
    if (pin_last == NULL)
        return false;
    for (k = 0; k < sim_pin_count; k++)
        pin_last[k] = -1;
    if (opt.pins == NULL)
        return true;
    pins_out = fopen(opt.pins, "w");
    if (pins_out == NULL) {
        el_host_error("cannot write %s: %s", opt.pins, strerror(errno));
        return false;
    }
    {
        size_t n = strlen(opt.pins);
        pins_vcd = n > 4u && strcasecmp(opt.pins + n - 4u, ".vcd") == 0;
    }
    if (pins_vcd) {
        fprintf(pins_out, "$comment EasyLab pins of model %s on the %s $end\n$timescale 1ps $end\n"
                          "$scope module pins $end\n", el_model_name, sim_mcu);
        for (k = 0; k < sim_pin_count; k++)
            fprintf(pins_out, "$var wire %d %c %s%s $end\n", sim_pins[k].kind == SIM_PIN_PWM ? 8 : 1, pin_id(k),
                    sim_pins[k].name, sim_pins[k].kind == SIM_PIN_PWM ? "_pwm" : "");
        fputs("$upscope $end\n$enddefinitions $end\n", pins_out);
    } else {
        fputs("cycle,time_us,pin,value\n", pins_out);
    }
    for (k = 0; k < sim_pin_count; k++) {
        const sim_pin_t *p = &sim_pins[k];
        if (p->kind == SIM_PIN_LEVEL) {
            avr_irq_register_notify(pin_irq(p->port, p->bit), pin_changed, (void *)(uintptr_t)k);
        } else {
            uint16_t port_addr = p->port >= 'H' ? (uint16_t)(0x102u + 3u * (uint16_t)(p->port - 'H' -
                                                                                      (p->port > 'I' ? 1 : 0)))
                                                : (uint16_t)(0x22u + 3u * (uint16_t)(p->port - 'A'));
            avr_irq_register_notify(avr_iomem_getirq(avr, p->ocr, NULL, AVR_IOMEM_IRQ_ALL), pwm_reg_written, NULL);
            avr_irq_register_notify(avr_iomem_getirq(avr, p->tccra, NULL, AVR_IOMEM_IRQ_ALL), pwm_reg_written,
                                    NULL);
            avr_irq_register_notify(avr_iomem_getirq(avr, port_addr, NULL, AVR_IOMEM_IRQ_ALL), pwm_reg_written,
                                    NULL);
        }
    }
    return true;
}

/* ---- UARTs ---- */

static void uart_output(struct avr_irq_t *irq, uint32_t value, void *param)
{
    uart_t *u = (uart_t *)param;
    uint8_t b = (uint8_t)value;
    (void)irq;
    if (u->fd < 0)
        return;
    if (write(u->fd, &b, 1) < 0 && (errno == EPIPE || errno == ECONNRESET) && u->mode == U_TCP) {
        close(u->fd);
        u->fd = -1;
    }
}

static void uart_xon(struct avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq;
    (void)value;
    ((uart_t *)param)->xoff = false;
}

static void uart_xoff(struct avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq;
    ((uart_t *)param)->xoff = value != 0u;
}

static bool set_nonblocking(int fd)
{
    int flags = fcntl(fd, F_GETFL);
    return flags >= 0 && fcntl(fd, F_SETFL, flags | O_NONBLOCK) == 0;
}

static bool uart_open(uart_t *u)
{
    u->fd = u->listen_fd = u->keep_fd = -1;
    if (u->mode == U_PTY) {
        int master, slave;
        struct termios tio;
        char name[256];
        if (openpty(&master, &slave, name, NULL, NULL) != 0) {
            el_host_error("uart%c: cannot make a pseudo-terminal: %s", u->name, strerror(errno));
            return false;
        }
        if (tcgetattr(slave, &tio) == 0) {
            cfmakeraw(&tio);
            tcsetattr(slave, TCSANOW, &tio);
        }
        unlink(u->arg);
        if (symlink(name, u->arg) != 0) {
            el_host_error("uart%c: cannot make the link %s: %s", u->name, u->arg, strerror(errno));
            close(master);
            close(slave);
            return false;
        }
        u->link_made = true;
        set_nonblocking(master);
        u->fd = master;
        u->keep_fd = slave;
        fprintf(stderr, "%s: uart%c on %s -> %s\n", el_host_prog, u->name, u->arg, name);
    } else if (u->mode == U_TCP) {
        struct sockaddr_in sa;
        socklen_t len = sizeof sa;
        int one = 1;
        char *end;
        long port = strtol(u->arg, &end, 10);
        if (*end != '\0' || port < 0 || port > 65535) {
            el_host_error("uart%c: bad TCP port '%s'", u->name, u->arg);
            return false;
        }
        u->listen_fd = socket(AF_INET, SOCK_STREAM, 0);
        if (u->listen_fd < 0)
            return false;
        setsockopt(u->listen_fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
        memset(&sa, 0, sizeof sa);
        sa.sin_family = AF_INET;
        sa.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        sa.sin_port = htons((uint16_t)port);
        if (bind(u->listen_fd, (struct sockaddr *)&sa, sizeof sa) != 0 || listen(u->listen_fd, 1) != 0 ||
            getsockname(u->listen_fd, (struct sockaddr *)&sa, &len) != 0) {
            el_host_error("uart%c: cannot listen on port %ld: %s", u->name, port, strerror(errno));
            return false;
        }
        set_nonblocking(u->listen_fd);
        fprintf(stderr, "%s: uart%c on tcp 127.0.0.1:%u\n", el_host_prog, u->name, (unsigned)ntohs(sa.sin_port));
    } else if (u->mode == U_FILE) {
        u->fd = open(u->arg, O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (u->fd < 0) {
            el_host_error("uart%c: cannot write %s: %s", u->name, u->arg, strerror(errno));
            return false;
        }
    }
    return true;
}

/* Read what clients sent and hand it to the MCU while its UART takes it. */
static void uart_service(uart_t *u)
{
    if (u->mode == U_TCP && u->fd < 0 && u->listen_fd >= 0) {
        int c = accept(u->listen_fd, NULL, NULL);
        if (c >= 0) {
            set_nonblocking(c);
            u->fd = c;
        }
    }
    if ((u->mode == U_PTY || u->mode == U_TCP) && u->fd >= 0 && u->in_len < sizeof u->in) {
        ssize_t n = read(u->fd, u->in + u->in_len, sizeof u->in - u->in_len);
        if (n > 0)
            u->in_len += (size_t)n;
        else if (n == 0 && u->mode == U_TCP) {
            close(u->fd);
            u->fd = -1;
        }
    }
    if (u->in_len > 0u && u->uart != NULL && avr_regbit_get(avr, u->uart->rxen)) {
        size_t sent = 0;
        avr_irq_t *in = avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ((uint32_t)u->name), UART_IRQ_INPUT);
        while (sent < u->in_len && !u->xoff && !uart_fifo_isfull(&u->uart->input)) {
            avr_raise_irq(in, u->in[sent]);
            sent++;
        }
        memmove(u->in, u->in + sent, u->in_len - sent);
        u->in_len -= sent;
    }
}

static bool clients_connected(void)
{
    int n;
    for (n = 0; n < 4; n++) {
        uart_t *u = &uarts[n];
        if (u->mode == U_TCP && u->fd < 0)
            return false;
        if (u->mode == U_PTY) {
            struct pollfd p = {u->fd, POLLIN, 0};
            if (poll(&p, 1, 0) < 0 || (p.revents & POLLHUP))
                return false;
        }
    }
    return true;
}

static void wait_for_clients(void)
{
    int n;
    /* A pty reports a hang-up while nobody holds its other side: let go of
     * ours, wait, then hold it again so that clients may come and go. */
    for (n = 0; n < 4; n++)
        if (uarts[n].mode == U_PTY && uarts[n].keep_fd >= 0) {
            close(uarts[n].keep_fd);
            uarts[n].keep_fd = -1;
        }
    fprintf(stderr, "%s: waiting for the UARTs' clients\n", el_host_prog);
    while (!stop_signal) {
        for (n = 0; n < 4; n++)
            if (uarts[n].mode == U_TCP && uarts[n].fd < 0)
                uart_service(&uarts[n]);
        if (clients_connected())
            break;
        usleep(10000);
    }
    for (n = 0; n < 4; n++)
        if (uarts[n].mode == U_PTY)
            uarts[n].keep_fd = open(uarts[n].arg, O_RDWR | O_NOCTTY);
}

static avr_uart_t *find_uart(char name)
{
    avr_io_t *io;
    for (io = avr->io_port; io != NULL; io = io->next)
        if (strcmp(io->kind, "uart") == 0 && ((avr_uart_t *)io)->name == name)
            return (avr_uart_t *)io;
    return NULL;
}

/* ---- EEPROM ---- */

/* The simulated EEPROM's bytes. simavr 1.6's EEPROM ioctls refuse a
 * request for the whole EEPROM (an off-by-one) and report success as -1:
 * ask for a pointer to its buffer instead, which GET hands out. */
static uint8_t *eeprom_bytes(void)
{
    avr_eeprom_desc_t ee;
    ee.ee = NULL;
    ee.offset = 0;
    ee.size = 1;
    (void)avr_ioctl(avr, AVR_IOCTL_EEPROM_GET, &ee);
    return ee.ee;
}

static bool nvram_load(void)
{
    uint8_t *buf, *mem;
    FILE *f;
    size_t n;
    if (opt.nvram == NULL)
        return true;
    f = fopen(opt.nvram, "rb");
    if (f == NULL)
        return errno == ENOENT; /* none yet: erased */
    buf = malloc(sim_nv_size + 1u);
    n = buf ? fread(buf, 1, sim_nv_size + 1u, f) : 0;
    fclose(f);
    if (buf == NULL || n != sim_nv_size) {
        el_host_error("--nvram %s: not an EEPROM image of the %s (%lu bytes)", opt.nvram, sim_mcu,
                      (unsigned long)sim_nv_size);
        free(buf);
        return false;
    }
    mem = eeprom_bytes();
    if (mem == NULL) {
        el_host_error("cannot reach the simulated EEPROM");
        free(buf);
        return false;
    }
    memcpy(mem, buf, sim_nv_size);
    free(buf);
    return true;
}

static bool nvram_save(void)
{
    const uint8_t *mem;
    FILE *f;
    bool ok;
    if (opt.nvram == NULL)
        return true;
    mem = eeprom_bytes();
    if (mem == NULL) {
        el_host_error("cannot reach the simulated EEPROM");
        return false;
    }
    f = fopen(opt.nvram, "wb");
    ok = f != NULL && fwrite(mem, 1, sim_nv_size, f) == sim_nv_size;
    if (f != NULL && fclose(f) != 0)
        ok = false;
    if (!ok)
        el_host_error("cannot write --nvram %s: %s", opt.nvram, strerror(errno));
    return ok;
}

/* ---- the run ---- */

static void on_signal(int sig)
{
    (void)sig;
    stop_signal = 1;
}

static uint64_t slept_cycles;

/* The CPU sleeps until the next event: skip to it at once (and count the
 * cycles asleep for --report); in real time the main loop keeps pace. */
static void sim_sleep(avr_t *a, avr_cycle_count_t how_long)
{
    (void)a;
    slept_cycles += how_long + 1u;
}

static void logger(avr_t *a, const int level, const char *format, va_list ap)
{
    if (level > LOG_WARNING || (a != NULL && level > a->log))
        return;
    fprintf(stderr, "%s: simavr: ", el_host_prog);
    vfprintf(stderr, format, ap);
}

static uint64_t wall_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000000u + (uint64_t)ts.tv_nsec;
}

int main(int argc, char **argv)
{
    elf_firmware_t fw;
    struct sigaction sa;
    uint64_t start_ns, next_service = 0;
    int r, n, state, saved_stdout;
    const char *elf;

    if (argc > 0 && argv[0] != NULL) {
        const char *slash = strrchr(argv[0], '/');
        el_host_prog = slash ? slash + 1 : argv[0];
    }
    r = parse_args(argc, argv);
    if (r != EXIT_OK)
        return r == EXIT_OK + 100 ? EXIT_OK : r;
    elf = opt.elf ? opt.elf : sim_elf_default;

    avr_global_logger_set(logger);
    memset(&fw, 0, sizeof fw);
    /* libsimavr prints while loading: keep stdout clean. */
    fflush(stdout);
    saved_stdout = dup(1);
    n = open("/dev/null", O_WRONLY);
    if (n >= 0) {
        dup2(n, 1);
        close(n);
    }
    r = elf_read_firmware(elf, &fw);
    avr = avr_make_mcu_by_name(sim_mcu);
    if (r == 0 && avr != NULL) {
        avr_init(avr);
        avr_load_firmware(avr, &fw);
    }
    fflush(stdout);
    if (saved_stdout >= 0) {
        dup2(saved_stdout, 1);
        close(saved_stdout);
    }
    if (r != 0) {
        el_host_error("cannot read the firmware %s", elf);
        return EXIT_USAGE;
    }
    if (avr == NULL) {
        el_host_error("libsimavr does not know the %s", sim_mcu);
        return EXIT_USAGE;
    }
    avr->frequency = sim_clock_hz;
    avr->avcc = 1023; /* mV: ADC counts = millivolts, exactly */
    avr->vcc = 5000;
    avr->log = LOG_ERROR;
    avr->sleep = sim_sleep;

    /* Inputs first, then outputs: a failed start creates no trace file. */
    hw_state = calloc(sim_hw_count ? sim_hw_count : 1u, sizeof *hw_state);
    if (hw_state == NULL)
        return EXIT_RUN;
    if ((opt.stimulus != NULL && !el_host_stimulus_load(opt.stimulus)) || !nvram_load() ||
        !sim_chips_init(avr, opt.chips))
        return EXIT_USAGE;
    if ((opt.trace != NULL && !el_host_trace_open(opt.trace)) || !pins_open())
        return EXIT_USAGE;

    for (n = 0; n < 4; n++) {
        uart_t *u = &uarts[n];
        uint32_t flags = 0;
        u->name = (char)('0' + n);
        u->fd = u->listen_fd = u->keep_fd = -1;
        if (strchr(sim_uarts, u->name) == NULL)
            continue;
        u->uart = find_uart(u->name);
        if (avr_ioctl(avr, AVR_IOCTL_UART_GET_FLAGS(u->name), &flags) == 0) {
            flags &= ~(uint32_t)(AVR_UART_FLAG_STDIO | AVR_UART_FLAG_POLL_SLEEP);
            avr_ioctl(avr, AVR_IOCTL_UART_SET_FLAGS(u->name), &flags);
        }
        avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ((uint32_t)u->name), UART_IRQ_OUTPUT),
                                uart_output, u);
        avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ((uint32_t)u->name), UART_IRQ_OUT_XON),
                                uart_xon, u);
        avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ((uint32_t)u->name), UART_IRQ_OUT_XOFF),
                                uart_xoff, u);
        if (!uart_open(u))
            return EXIT_USAGE;
    }
    avr_register_io_write(avr, GPIOR0_ADDR, gpior0_write, NULL);

    memset(&sa, 0, sizeof sa);
    sigemptyset(&sa.sa_mask);
    sa.sa_handler = on_signal;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    sa.sa_handler = SIG_IGN;
    sigaction(SIGPIPE, &sa, NULL);

    if (opt.halt) /* read by el_port_init of a debug build (EL_AVR_SIM_HALT) */
        avr->data[GPIOR2_ADDR] = 0xA5u;
    if (opt.wait)
        wait_for_clients();
    start_ns = wall_ns();
    for (;;) {
        state = avr_run(avr);
        if (state == cpu_Done || state == cpu_Crashed || stop_run || stop_signal)
            break;
        if (opt.has_cycles && avr->cycle >= opt.cycles)
            break;
        if (busy_count != 0u)
            check_deliveries();
        if (avr->cycle >= next_service) {
            next_service = avr->cycle + SERVICE_CYCLES;
            /* A firmware without the simulation hooks never reaches T
             * logically: end a second of CPU time after T if no instant
             * came at all. (One that has instants gets there; a debugger
             * may halt logical time for as long as it likes, --halt from
             * the start, as on the host board.) */
            if (opt.has_duration && instants == 0u && !opt.halt &&
                avr->cycle / (sim_clock_hz / 1000000u) > opt.duration_us + 1000000u) {
                el_host_error("warning: no instant at or after %llu us came by %llu us of CPU time (a build "
                              "without --sim?): stopped", (unsigned long long)opt.duration_us,
                              (unsigned long long)(avr->cycle / (sim_clock_hz / 1000000u)));
                break;
            }
            for (n = 0; n < 4; n++)
                if (uarts[n].mode == U_PTY || uarts[n].mode == U_TCP)
                    uart_service(&uarts[n]);
            if (!opt.fast) {
                uint64_t due = start_ns + avr->cycle * 1000000000u / sim_clock_hz;
                uint64_t now = wall_ns();
                if (due > now + 1000000u) {
                    struct timespec ts;
                    ts.tv_sec = (time_t)((due - now) / 1000000000u);
                    ts.tv_nsec = (long)((due - now) % 1000000000u);
                    nanosleep(&ts, NULL);
                }
            }
        }
    }
    if (state == cpu_Crashed) {
        el_host_error("the firmware crashed at cycle %llu (pc 0x%05x)", (unsigned long long)avr->cycle,
                      (unsigned)avr->pc);
        exit_status = EXIT_RUN;
    }
    if (!el_host_trace_close())
        exit_status = EXIT_RUN;
    if (pins_out != NULL && fclose(pins_out) != 0)
        exit_status = EXIT_RUN;
    if (!nvram_save() || !sim_chips_save())
        exit_status = EXIT_RUN;
    if (opt.report) {
        fprintf(stderr, "%s: cycles %llu (asleep %llu), instants %llu, time %llu us\n", el_host_prog,
                (unsigned long long)avr->cycle, (unsigned long long)slept_cycles, (unsigned long long)instants,
                (unsigned long long)el_sim_now_us);
    }
    for (n = 0; n < 4; n++) {
        if (uarts[n].link_made)
            unlink(uarts[n].arg);
        if (uarts[n].fd >= 0)
            close(uarts[n].fd);
    }
    el_host_stimulus_free();
    return exit_status;
}
