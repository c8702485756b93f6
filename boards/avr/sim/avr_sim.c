/* EasyLab AVR board: the simavr harness (docs/boards.md, "Simulation").
 *
 * Runs a firmware built with `easylab build --board avr --sim` in simavr
 * (Debian's libsimavr) with the host board's command line where it makes
 * sense, so that one stimulus gives one trace on every board (what every
 * harness shares, options, links, instants, pins and pace, is
 * sim/sim_harness.c; this file is simavr's side):
 *
 *   NAME-sim [--fast] [--duration T] [--cycles N] [--stimulus S.csv]
 *            [--trace T.csv|T.vcd] [--pins P.csv|P.vcd] [--nvram FILE]
 *            [--chips DIR] [--uartN pty:LINK|tcp:PORT|file:PATH|null] [--wait] [--halt]
 *            [--elf FILE] [--report] [--help]
 *
 * Instants: the simulation build's el_port_inputs and el_port_instant write
 * a marker to GPIOR0, which this harness hooks. At the inputs marker of an
 * instant (after the outputs due then were published, before devices are
 * read) it applies the stimulus due by then, exactly as the host board does:
 * params and vars are written into the MCU's RAM, device `out` data are put
 * on the hardware the build maps them to (an ADC channel's voltage, an input
 * pin's level, line camera frames on a UART, quadrature edges on encoder
 * pins, a value of a chip on a bus, a UART or pins: avr_chips.c,
 * sim/sim_chips.c), and the
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
 *
 * Bus timing (bench/bench_distribution.py): with EASYLAB_UART_LOG=DIR in
 * the environment, DIR/<program>.uart.csv gets a line per UART byte,
 * `cycle,uart,dir,byte,cycles_per_byte`: `rx` when the byte enters the
 * UART (its reception ends cycles_per_byte later than the one before it),
 * `tx` when the firmware writes it (its transmission starts then).
 */
#include "sim_model.h"
#include "avr_chips.h"
#include "sim_chips.h"

const char sim_chips_help[] =
    "  --chips DIR       the memories of the chips on the buses (DIR/DEVICE.bin: an EEPROM's),\n"
    "                    read at start (erased when absent) and written at the end\n";

#include "sim_avr.h"
#include "sim_elf.h"
#include "sim_core.h"
#include "sim_cycle_timers.h"
#include "sim_irq.h"
#include "avr_ioport.h"
#include "avr_uart.h"
#include "avr_adc.h"
#include "avr_eeprom.h"

#include <fcntl.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

DEFINE_FIFO(uint16_t, uart_fifo); /* simavr's UART input FIFO accessors */

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

static avr_t *avr;
static unsigned busy_count; /* deliveries on their way: UART frames, encoder edges */
static uint64_t slept_cycles;

/* simavr's side of each UART (the link itself is sim_links[n]). */
static struct {
    avr_uart_t *uart;
    bool xoff;
    bool delivering; /* line camera frames on their way */
} uarts[4];

/* ---- the MCU's RAM ---- */

void sim_ram_read(uint16_t addr, void *dst, size_t n)
{
    memcpy(dst, avr->data + addr, n);
}

void sim_ram_write(uint16_t addr, const void *src, size_t n)
{
    memcpy(avr->data + addr, src, n);
}

/* The instant's tick: el_avr_sim_tick, little-endian, 2 or 4 bytes (the
 * firmware's el_tick_t: sim_tick_size). */
static uint64_t read_tick(void)
{
    uint8_t b[4] = {0u, 0u, 0u, 0u};
    uint8_t n = sim_tick_size == 2u ? 2u : 4u;
    sim_ram_read(sim_tick_addr, b, n);
    return sim_tick_extend_bits((uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24,
                                8u * n);
}

/* ---- hardware behind device data ---- */

static avr_irq_t *pin_irq(char port, uint8_t bit)
{
    return avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ(port), bit);
}

static void set_busy(void)
{
    avr->data[GPIOR1_ADDR] = busy_count != 0u ? 1u : 0u;
}

static avr_cycle_count_t encoder_edge(avr_t *a, avr_cycle_count_t when, void *param)
{
    sim_hw_state_t *s = (sim_hw_state_t *)param;
    const sim_hw_t *h = &sim_hw[s - sim_hw_state];
    uint8_t ab, changed;
    (void)a;
    if (s->position == s->target) {
        s->busy = false;
        busy_count--;
        set_busy();
        return 0;
    }
    s->position += s->target > s->position ? 1 : -1;
    ab = sim_quadrature(s->position);
    changed = (uint8_t)(ab ^ s->ab);
    s->ab = ab;
    if (changed & 2u)
        avr_raise_irq(pin_irq((char)(h->a >> 8), (uint8_t)(h->a & 0xFFu)), (ab >> 1) & 1u);
    if (changed & 1u)
        avr_raise_irq(pin_irq((char)(h->b >> 8), (uint8_t)(h->b & 0xFFu)), ab & 1u);
    return when + ENCODER_EDGE_CYCLES;
}

bool sim_drive_hardware(uint16_t k)
{
    const sim_hw_t *h = &sim_hw[k];
    sim_hw_state_t *s = &sim_hw_state[k];
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
        if (uarts[h->a].uart == NULL || !avr_regbit_get(avr, uarts[h->a].uart->rxen))
            return true; /* the driver is not listening: the frame is lost, as on a board */
        for (i = 0; i < 4; i++)
            avr_raise_irq(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ((uint32_t)('0' + h->a)), UART_IRQ_INPUT),
                          frame[i]);
        if (!uarts[h->a].delivering) {
            uarts[h->a].delivering = true;
            busy_count++;
        }
        return true;
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

static void gpior0_write(struct avr_t *a, avr_io_addr_t addr, uint8_t v, void *param)
{
    (void)param;
    a->data[addr] = v;
    if (v == MARK_INPUTS) {
        sim_instant_inputs(read_tick());
        set_busy();
    } else if (v == MARK_INSTANT) {
        sim_instant_record(read_tick());
    }
}

/* Line camera frames delivered: the UART's FIFO is empty and read. */
static void check_deliveries(void)
{
    int n;
    for (n = 0; n < 4; n++) {
        if (!uarts[n].delivering || uarts[n].uart == NULL)
            continue;
        if (uart_fifo_isempty(&uarts[n].uart->input) && !avr_regbit_get(avr, uarts[n].uart->rxc.raised)) {
            uarts[n].delivering = false;
            busy_count--;
            set_busy();
        }
    }
}

/* ---- pins ---- */

const char *sim_pin_name(uint16_t k, bool *pwm)
{
    *pwm = sim_pins[k].kind == SIM_PIN_PWM;
    return sim_pins[k].name;
}

static int pwm_duty(const sim_pin_t *p)
{
    if ((avr->data[p->tccra] >> p->com_bit) & 1u)
        return avr->data[p->ocr];
    return (avr->data[avr_port_addr(p->port)] >> p->bit) & 1u ? 255 : 0;
}

static void pin_changed(struct avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq;
    sim_pin_record((uint16_t)(uintptr_t)param, (int)(value & 1u), avr->cycle);
}

static void pwm_reg_written(struct avr_irq_t *irq, uint32_t value, void *param)
{
    uint16_t k;
    (void)irq;
    (void)value;
    (void)param;
    for (k = 0; k < sim_pin_count; k++)
        if (sim_pins[k].kind == SIM_PIN_PWM)
            sim_pin_record(k, pwm_duty(&sim_pins[k]), avr->cycle);
}

static void watch_pins(void)
{
    uint16_t k;
    for (k = 0; k < sim_pin_count; k++) {
        const sim_pin_t *p = &sim_pins[k];
        if (p->kind == SIM_PIN_LEVEL) {
            avr_irq_register_notify(pin_irq(p->port, p->bit), pin_changed, (void *)(uintptr_t)k);
        } else {
            avr_irq_register_notify(avr_iomem_getirq(avr, p->ocr, NULL, AVR_IOMEM_IRQ_ALL), pwm_reg_written, NULL);
            avr_irq_register_notify(avr_iomem_getirq(avr, p->tccra, NULL, AVR_IOMEM_IRQ_ALL), pwm_reg_written,
                                    NULL);
            avr_irq_register_notify(avr_iomem_getirq(avr, avr_port_addr(p->port), NULL, AVR_IOMEM_IRQ_ALL),
                                    pwm_reg_written, NULL);
        }
    }
}

/* ---- UARTs ---- */

static FILE *uart_log; /* EASYLAB_UART_LOG: every byte with its cycle */

static void uart_log_open(void)
{
    const char *dir = getenv("EASYLAB_UART_LOG");
    char path[4096];
    if (dir == NULL || dir[0] == '\0')
        return;
    if (snprintf(path, sizeof path, "%s/%s.uart.csv", dir, el_host_prog) >= (int)sizeof path ||
        (uart_log = fopen(path, "w")) == NULL) {
        el_host_error("EASYLAB_UART_LOG: cannot write %s/%s.uart.csv", dir, el_host_prog);
        return;
    }
    fputs("cycle,uart,dir,byte,cycles_per_byte\n", uart_log);
}

static void uart_log_byte(const sim_link_t *u, const char *dir, uint8_t byte)
{
    if (uart_log != NULL)
        fprintf(uart_log, "%llu,%c,%s,%u,%llu\n", (unsigned long long)avr->cycle, u->name, dir, (unsigned)byte,
                (unsigned long long)uarts[u - sim_links].uart->cycles_per_byte);
}

static void uart_output(struct avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq;
    uart_log_byte((sim_link_t *)param, "tx", (uint8_t)value);
    sim_link_output((sim_link_t *)param, (uint8_t)value);
    sim_chips_uart_byte((uint8_t)((sim_link_t *)param - sim_links), (uint8_t)value);
}

static void uart_xon(struct avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq;
    (void)value;
    uarts[(sim_link_t *)param - sim_links].xoff = false;
}

static void uart_xoff(struct avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq;
    uarts[(sim_link_t *)param - sim_links].xoff = value != 0u;
}

static avr_uart_t *find_uart(char name)
{
    avr_io_t *io;
    for (io = avr->io_port; io != NULL; io = io->next)
        if (strcmp(io->kind, "uart") == 0 && ((avr_uart_t *)io)->name == name)
            return (avr_uart_t *)io;
    return NULL;
}

/* Hook the MCU's UARTs: their output goes to the links. */
static void hook_uarts(void)
{
    int n;
    for (n = 0; n < 4; n++) {
        char name = (char)('0' + n);
        uint32_t flags = 0;
        if (strchr(sim_uarts, name) == NULL)
            continue;
        uarts[n].uart = find_uart(name);
        if (avr_ioctl(avr, AVR_IOCTL_UART_GET_FLAGS(name), &flags) == 0) {
            flags &= ~(uint32_t)(AVR_UART_FLAG_STDIO | AVR_UART_FLAG_POLL_SLEEP);
            avr_ioctl(avr, AVR_IOCTL_UART_SET_FLAGS(name), &flags);
        }
        avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ((uint32_t)name), UART_IRQ_OUTPUT),
                                uart_output, &sim_links[n]);
        avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ((uint32_t)name), UART_IRQ_OUT_XON),
                                uart_xon, &sim_links[n]);
        avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ((uint32_t)name), UART_IRQ_OUT_XOFF),
                                uart_xoff, &sim_links[n]);
    }
}

/* Hand what the clients sent to the MCU while its UART takes it. */
static void feed_uarts(void)
{
    int n;
    for (n = 0; n < 4; n++) {
        sim_link_t *u = &sim_links[n];
        size_t sent = 0, ready;
        avr_irq_t *in;
        if (uarts[n].uart == NULL || !avr_regbit_get(avr, uarts[n].uart->rxen))
            continue;
        ready = sim_link_ready(u, avr->cycle, uart_fifo_isempty(&uarts[n].uart->input),
                               uarts[n].uart->cycles_per_byte);
        if (ready == 0u)
            continue;
        in = avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ((uint32_t)u->name), UART_IRQ_INPUT);
        while (sent < ready && !uarts[n].xoff && !uart_fifo_isfull(&uarts[n].uart->input)) {
            uart_log_byte(u, "rx", u->in[sent]);
            avr_raise_irq(in, u->in[sent]);
            sent++;
        }
        sim_link_consume(u, sent);
    }
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

/* ---- the run ---- */

/* In real time a sleeping CPU must still take what a peer sends within
 * 20 us (a remote-execution host's values are due at a deadline of 1 ms):
 * this timer bounds every sleep, so the loop below feeds the UARTs. */
static avr_cycle_count_t wake_to_listen(avr_t *a, avr_cycle_count_t when, void *param)
{
    (void)a;
    (void)param;
    return when + sim_clock_hz / 50000u;
}

/* The CPU sleeps until the next event: skip to it at once (and count the
 * cycles asleep for --report); in real time sim_service keeps pace. */
static void sim_sleep(avr_t *a, avr_cycle_count_t how_long)
{
    (void)a;
    slept_cycles += how_long + 1u;
}

/* What the chip models a model brings may do (sim/sim_chips.h). */
uint64_t sim_board_now_us(void)
{
    return avr->cycle / (sim_clock_hz / 1000000u);
}

/* simavr's UART takes the byte into its receive FIFO, which hands it to
 * the firmware one character time (cycles_per_byte) after the byte before
 * it, and drops it while the receiver is off. */
void sim_board_uart_receive(uint8_t uart, uint8_t byte)
{
    if (uart >= 4u || uarts[uart].uart == NULL)
        return;
    uart_log_byte(&sim_links[uart], "rx", byte);
    avr_raise_irq(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ((uint32_t)('0' + uart)), UART_IRQ_INPUT), byte);
}

void sim_board_pin_drive(uint16_t pin, bool level)
{
    avr_raise_irq(avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ('A' + (pin >> 3)), pin & 7u), level ? 1u : 0u);
}

static void logger(avr_t *a, const int level, const char *format, va_list ap)
{
    if (level > LOG_WARNING || (a != NULL && level > a->log))
        return;
    fprintf(stderr, "%s: simavr: ", el_host_prog);
    vfprintf(stderr, format, ap);
}

int main(int argc, char **argv)
{
    elf_firmware_t fw;
    int r, n, state, saved_stdout;
    uint8_t *eeprom;

    r = sim_parse_args(argc, argv, "--elf", "simavr");
    if (r != SIM_EXIT_OK)
        return r == SIM_EXIT_HELP ? SIM_EXIT_OK : r;

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
    r = elf_read_firmware(sim_opt.firmware, &fw);
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
        el_host_error("cannot read the firmware %s", sim_opt.firmware);
        return SIM_EXIT_USAGE;
    }
    if (avr == NULL) {
        el_host_error("libsimavr does not know the %s", sim_mcu);
        return SIM_EXIT_USAGE;
    }
    avr->frequency = sim_clock_hz;
    avr->avcc = 1023; /* mV: ADC counts = millivolts, exactly */
    avr->vcc = 5000;
    avr->log = LOG_ERROR;
    avr->sleep = sim_sleep;
    eeprom = eeprom_bytes();
    if (eeprom == NULL) {
        el_host_error("cannot reach the simulated EEPROM");
        return SIM_EXIT_RUN;
    }

    hook_uarts();
    uart_log_open();
    /* Inputs first (the chips' memories, then sim_start's): a failed start
     * creates no trace file. */
    if (!avr_chips_attach(avr) || !sim_chips_start(sim_opt.chips) || !sim_start(eeprom))
        return SIM_EXIT_USAGE;
    watch_pins();
    avr_register_io_write(avr, GPIOR0_ADDR, gpior0_write, NULL);
    if (sim_opt.halt) /* read by el_port_init of a debug build (EL_AVR_SIM_HALT) */
        avr->data[GPIOR2_ADDR] = 0xA5u;

    if (!sim_opt.fast)
        avr_cycle_timer_register(avr, sim_clock_hz / 50000u, wake_to_listen, NULL);
    for (;;) {
        state = avr_run(avr);
        if (state == cpu_Done || state == cpu_Crashed || sim_stop || sim_stop_signal)
            break;
        if (sim_opt.has_cycles && avr->cycle >= sim_opt.cycles)
            break;
        if (busy_count != 0u)
            check_deliveries();
        if (!sim_service(avr->cycle))
            break;
        feed_uarts();
    }
    if (state == cpu_Crashed) {
        el_host_error("the firmware crashed at cycle %llu (pc 0x%05x)", (unsigned long long)avr->cycle,
                      (unsigned)avr->pc);
        sim_exit_status = SIM_EXIT_RUN;
    }
    if (!sim_chips_finish())
        sim_exit_status = SIM_EXIT_RUN;
    if (uart_log != NULL && fclose(uart_log) != 0)
        el_host_error("EASYLAB_UART_LOG: writing the log failed");
    return sim_finish(avr->cycle, slept_cycles, eeprom_bytes());
}
