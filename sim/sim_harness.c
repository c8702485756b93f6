/* EasyLab: what the simulator harnesses of the boards share (see
 * sim_harness.h). */
#include "sim_harness.h"

#include "el_crc16.h"
#include "sim_chips.h"

#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <pty.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/socket.h>
#if defined(__linux__)
#include <sys/prctl.h>
#endif
#include <termios.h>
#include <time.h>
#include <unistd.h>

const char *el_host_prog = "easylab-sim";
uint64_t el_sim_now_us;

uint64_t el_host_now_us(void)
{
    return el_sim_now_us;
}

sim_options_t sim_opt;
sim_link_t sim_links[4];
sim_hw_state_t *sim_hw_state;
uint64_t sim_instants;
bool sim_stop;
int sim_exit_status = SIM_EXIT_OK;
volatile sig_atomic_t sim_stop_signal;

/* ---- options ---- */

static void usage(FILE *f, const char *firmware_option, const char *simulator)
{
    fprintf(f,
            "usage: %s [--fast] [--duration T] [--cycles N] [--stimulus FILE.csv] [--trace FILE.csv|FILE.vcd]\n"
            "          [--trace-state] [--pins FILE.csv|FILE.vcd] [--nvram FILE] [--uartN pty:LINK|tcp:PORT|file:PATH|null]\n"
            "          [--rtu-frames] [--wait] [--halt] [%s FILE] [--report] [--help]\n"
            "Runs the %s firmware of model %s in %s.\n"
            "  --fast            flat out (default: in step with the wall clock)\n"
            "  --duration T      end at the first instant at or after T (10s, 500ms, 250us, 2m, 1h)\n"
            "  --cycles N        end after N CPU cycles\n"
            "  --stimulus FILE   device data, params and vars over time (the host board's format)\n"
            "  --trace FILE      items and charts at every instant (.csv or .vcd, the host board's format)\n"
            "  --trace-state     the trace also records the devices' `state` fields (DEVICE.FIELD, after the\n"
            "                    items), read from the MCU's RAM, as the host board's --trace-state\n"
            "  --pins FILE       the model's pins as they change (.csv: cycle,time_us,pin,value; .vcd);\n"
            "                    a PWM output as its duty 0..255\n"
            "  --nvram FILE      the EEPROM (%lu bytes), read at start and written at the end\n"
            "%s"
            "  --uartN SPEC      UART N (of %s) on a pseudo-terminal (symlink LINK), TCP port, file or nothing\n"
            "  --rtu-frames      in real time, the UARTs' clients speak Modbus RTU: each frame reaches\n"
            "                    the MCU followed by 5 ms of silence, even when frames came together\n"
            "                    (the pauses of a wire, which a pty does not keep)\n"
            "  --wait            hold the CPU until every pty and TCP UART has a client\n"
            "  --halt            halt at the first instant for the debugger (the host's --debug ...,halt)\n"
            "  %-17s run this firmware (default: %s)\n"
            "  --report          print cycles, instants and the logical time on stderr at the end\n",
            el_host_prog, firmware_option, sim_mcu, el_model_name, simulator, (unsigned long)sim_nv_size, sim_chips_help,
            sim_uarts,
            firmware_option, sim_firmware_default);
}

static bool uart_option(const char *a)
{
    return strncmp(a, "--uart", 6) == 0 && a[6] >= '0' && a[6] <= '3' && a[7] == '\0';
}

static bool takes_value(const char *a, const char *firmware_option)
{
    static const char *const with_value[] = {"--duration", "--cycles", "--stimulus", "--trace", "--pins",
                                             "--nvram", "--chips"};
    size_t i;
    for (i = 0; i < sizeof with_value / sizeof with_value[0]; i++)
        if (strcmp(a, with_value[i]) == 0)
            return true;
    return strcmp(a, firmware_option) == 0 || uart_option(a);
}

static bool link_option(const char *a, const char *v)
{
    sim_link_t *u = &sim_links[a[6] - '0'];
    if (strchr(sim_uarts, a[6]) == NULL) {
        el_host_error("%s: the %s has no UART %c (UARTs: %s)", a, sim_mcu, a[6], sim_uarts);
        return false;
    }
    if (strncmp(v, "pty:", 4) == 0 && v[4] != '\0') {
        u->mode = SIM_LINK_PTY;
        u->arg = v + 4;
    } else if (strncmp(v, "tcp:", 4) == 0 && v[4] != '\0') {
        u->mode = SIM_LINK_TCP;
        u->arg = v + 4;
    } else if (strncmp(v, "file:", 5) == 0 && v[5] != '\0') {
        u->mode = SIM_LINK_FILE;
        u->arg = v + 5;
    } else if (strcmp(v, "null") == 0) {
        u->mode = SIM_LINK_NONE;
    } else {
        el_host_error("%s %s: give pty:LINK, tcp:PORT, file:PATH or null", a, v);
        return false;
    }
    return true;
}

int sim_parse_args(int argc, char **argv, const char *firmware_option, const char *simulator)
{
    int i;
    if (argc > 0 && argv[0] != NULL) {
        const char *slash = strrchr(argv[0], '/');
        el_host_prog = slash ? slash + 1 : argv[0];
    }
    for (i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        const char *why;
        if (strcmp(a, "--help") == 0) {
            usage(stdout, firmware_option, simulator);
            return SIM_EXIT_HELP;
        } else if (strcmp(a, "--fast") == 0) {
            sim_opt.fast = true;
        } else if (strcmp(a, "--wait") == 0) {
            sim_opt.wait = true;
        } else if (strcmp(a, "--rtu-frames") == 0) {
            sim_opt.rtu_frames = true;
        } else if (strcmp(a, "--halt") == 0) {
            sim_opt.halt = true;
        } else if (strcmp(a, "--report") == 0) {
            sim_opt.report = true;
        } else if (strcmp(a, "--trace-state") == 0) {
            el_host_trace_state = true;
        } else if (!takes_value(a, firmware_option)) {
            el_host_error("unknown option '%s' (--help lists them)", a);
            return SIM_EXIT_USAGE;
        } else if (v == NULL) {
            el_host_error("%s: a value must follow", a);
            return SIM_EXIT_USAGE;
        } else {
            i++;
            if (strcmp(a, "--duration") == 0) {
                if (!el_host_parse_duration(v, &sim_opt.duration_us, &why)) {
                    el_host_error("--duration %s: %s", v, why);
                    return SIM_EXIT_USAGE;
                }
                sim_opt.has_duration = true;
            } else if (strcmp(a, "--cycles") == 0) {
                char *end;
                errno = 0;
                sim_opt.cycles = strtoull(v, &end, 10);
                if (*v == '\0' || *end != '\0' || errno != 0) {
                    el_host_error("--cycles %s: give a whole number of CPU cycles", v);
                    return SIM_EXIT_USAGE;
                }
                sim_opt.has_cycles = true;
            } else if (strcmp(a, "--stimulus") == 0) {
                sim_opt.stimulus = v;
            } else if (strcmp(a, "--trace") == 0) {
                sim_opt.trace = v;
            } else if (strcmp(a, "--pins") == 0) {
                sim_opt.pins = v;
            } else if (strcmp(a, "--nvram") == 0) {
                sim_opt.nvram = v;
            } else if (strcmp(a, "--chips") == 0) {
                if (sim_chips_help[0] == '\0') {
                    el_host_error("--chips: the %s harness models no chips on buses", simulator);
                    return SIM_EXIT_USAGE;
                }
                sim_opt.chips = v;
            } else if (strcmp(a, firmware_option) == 0) {
                sim_opt.firmware = v;
            } else if (!link_option(a, v)) {
                return SIM_EXIT_USAGE;
            }
        }
    }
    if (sim_opt.firmware == NULL)
        sim_opt.firmware = sim_firmware_default;
    return SIM_EXIT_OK;
}

/* ---- serial links ---- */

static bool set_nonblocking(int fd)
{
    int flags = fcntl(fd, F_GETFL);
    return flags >= 0 && fcntl(fd, F_SETFL, flags | O_NONBLOCK) == 0;
}

static bool link_open(sim_link_t *u)
{
    if (u->mode == SIM_LINK_PTY) {
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
    } else if (u->mode == SIM_LINK_TCP) {
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
    } else if (u->mode == SIM_LINK_FILE) {
        u->fd = open(u->arg, O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (u->fd < 0) {
            el_host_error("uart%c: cannot write %s: %s", u->name, u->arg, strerror(errno));
            return false;
        }
    }
    return true;
}

bool sim_links_open(void)
{
    int n;
    for (n = 0; n < 4; n++) {
        sim_link_t *u = &sim_links[n];
        u->name = (char)('0' + n);
        u->fd = u->listen_fd = u->keep_fd = -1;
        u->frame_crc = EL_CRC16_INIT;
        if (strchr(sim_uarts, u->name) != NULL && !link_open(u))
            return false;
    }
    return true;
}

void sim_link_service(sim_link_t *u)
{
    if (u->mode == SIM_LINK_TCP && u->fd < 0 && u->listen_fd >= 0) {
        int c = accept(u->listen_fd, NULL, NULL);
        if (c >= 0) {
            int one = 1;
            set_nonblocking(c);
            /* each byte the MCU sends goes at once: Nagle's algorithm would
             * hold a frame's bytes for the peer's delayed acknowledgement */
            (void)setsockopt(c, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
            u->fd = c;
        }
    }
    if ((u->mode == SIM_LINK_PTY || u->mode == SIM_LINK_TCP) && u->fd >= 0 && u->in_len < sizeof u->in) {
        ssize_t n = read(u->fd, u->in + u->in_len, sizeof u->in - u->in_len);
        if (n > 0) {
            u->in_len += (size_t)n;
        } else if (n == 0 && u->mode == SIM_LINK_TCP) {
            close(u->fd);
            u->fd = -1;
        }
    }
}

/* Does p[0..n) start with a whole Modbus RTU frame (4 bytes or more, the
 * CRC over them and their CRC 0)? */
static bool starts_with_frame(const uint8_t *p, size_t n)
{
    uint16_t crc = EL_CRC16_INIT;
    size_t i;
    for (i = 0; i < n; i++) {
        crc = el_crc16_update(crc, p + i, 1u);
        if (i >= 3u && crc == 0u)
            return true;
    }
    return false;
}

static uint64_t cycles_of_ns(uint64_t ns)
{
    return ns * sim_clock_hz / 1000000000u;
}

static bool keeps_frames_apart(void)
{
    return sim_opt.rtu_frames && !sim_opt.fast; /* in lock-step every frame is answered before the next */
}

size_t sim_link_ready(sim_link_t *u, uint64_t cycle, bool idle, uint64_t char_cycles)
{
    uint16_t crc;
    size_t i, len;
    if (!keeps_frames_apart())
        return u->in_len;
    if (u->frame_ended) {
        /* The silence runs from the moment the receiver has the frame,
         * whether the next frame came yet or not: a master that kept the
         * pause itself (EASYLAB_BUS_GAP_US) must not wait it twice. */
        if (!idle)
            return 0u;
        if (!u->idle_seen) {
            u->idle_seen = true;
            u->idle_from = cycle;
        }
        if (cycle - u->idle_from < char_cycles + cycles_of_ns(SIM_RTU_PAUSE_NS))
            return 0u;
        u->frame_ended = false;
        u->frame_crc = EL_CRC16_INIT;
        u->frame_len = 0u;
    }
    if (u->in_len == 0u)
        return 0u;
    /* The frame ends where its CRC checks and a whole frame follows (frames
     * that came together); a frame still coming goes on as it comes. */
    crc = u->frame_crc;
    len = u->frame_len;
    for (i = 0; i + 1u < u->in_len; i++) {
        crc = el_crc16_update(crc, u->in + i, 1u);
        if (++len >= 4u && crc == 0u && starts_with_frame(u->in + i + 1u, u->in_len - i - 1u))
            return i + 1u;
    }
    return u->in_len;
}

void sim_link_consume(sim_link_t *u, size_t n)
{
    if (keeps_frames_apart() && n != 0u) {
        u->frame_crc = el_crc16_update(u->frame_crc, u->in, (uint16_t)n);
        u->frame_len += n;
        /* what went ends a frame (nothing follows yet, or a whole frame
         * does): a silence follows */
        if (u->frame_len >= 4u && u->frame_crc == 0u &&
            (n == u->in_len || starts_with_frame(u->in + n, u->in_len - n))) {
            u->frame_ended = true;
            u->idle_seen = false;
        }
    }
    memmove(u->in, u->in + n, u->in_len - n);
    u->in_len -= n;
}

void sim_link_output(sim_link_t *u, uint8_t byte)
{
    if (u->fd < 0)
        return;
    if (write(u->fd, &byte, 1) < 0 && (errno == EPIPE || errno == ECONNRESET) && u->mode == SIM_LINK_TCP) {
        close(u->fd);
        u->fd = -1;
    }
}

static bool clients_connected(void)
{
    int n;
    for (n = 0; n < 4; n++) {
        sim_link_t *u = &sim_links[n];
        if (u->mode == SIM_LINK_TCP && u->fd < 0)
            return false;
        if (u->mode == SIM_LINK_PTY) {
            struct pollfd p = {u->fd, POLLIN, 0};
            if (poll(&p, 1, 0) < 0 || (p.revents & POLLHUP))
                return false;
        }
    }
    return true;
}

void sim_wait_for_clients(void)
{
    int n;
    /* A pty reports a hang-up while nobody holds its other side: let go of
     * ours, wait, then hold it again so that clients may come and go. */
    for (n = 0; n < 4; n++)
        if (sim_links[n].mode == SIM_LINK_PTY && sim_links[n].keep_fd >= 0) {
            close(sim_links[n].keep_fd);
            sim_links[n].keep_fd = -1;
        }
    fprintf(stderr, "%s: waiting for the UARTs' clients\n", el_host_prog);
    while (!sim_stop_signal) {
        for (n = 0; n < 4; n++)
            if (sim_links[n].mode == SIM_LINK_TCP && sim_links[n].fd < 0)
                sim_link_service(&sim_links[n]);
        if (clients_connected())
            break;
        usleep(10000);
    }
    for (n = 0; n < 4; n++)
        if (sim_links[n].mode == SIM_LINK_PTY)
            sim_links[n].keep_fd = open(sim_links[n].arg, O_RDWR | O_NOCTTY);
}

/* ---- the EEPROM image ---- */

bool sim_nvram_load(uint8_t *mem)
{
    uint8_t *buf;
    FILE *f;
    size_t n;
    if (sim_opt.nvram == NULL)
        return true;
    f = fopen(sim_opt.nvram, "rb");
    if (f == NULL)
        return errno == ENOENT; /* none yet: erased */
    buf = malloc(sim_nv_size + 1u);
    n = buf ? fread(buf, 1, sim_nv_size + 1u, f) : 0;
    fclose(f);
    if (buf == NULL || n != sim_nv_size) {
        el_host_error("--nvram %s: not an EEPROM image of the %s (%lu bytes)", sim_opt.nvram, sim_mcu,
                      (unsigned long)sim_nv_size);
        free(buf);
        return false;
    }
    memcpy(mem, buf, sim_nv_size);
    free(buf);
    return true;
}

bool sim_nvram_save(const uint8_t *mem)
{
    FILE *f;
    bool ok;
    if (sim_opt.nvram == NULL)
        return true;
    f = fopen(sim_opt.nvram, "wb");
    ok = f != NULL && fwrite(mem, 1, sim_nv_size, f) == sim_nv_size;
    if (f != NULL && fclose(f) != 0)
        ok = false;
    if (!ok)
        el_host_error("cannot write --nvram %s: %s", sim_opt.nvram, strerror(errno));
    return ok;
}

/* ---- instants ---- */

/* Copy items of these kinds (bit per EL_K_) and the charts from the MCU
 * into the host-side mirrors of el_items and el_charts. */
static void mirror_from_mcu(unsigned kinds, bool charts)
{
    uint16_t i;
    uint8_t c;
    for (i = 0; i < el_item_count; i++) {
        if ((kinds & (1u << el_items[i].kind)) != 0u && sim_item_addr[i].addr != 0xFFFFu)
            sim_ram_read(sim_item_addr[i].addr, el_items[i].addr, sim_item_addr[i].size);
    }
    if (charts)
        for (c = 0; c < el_chart_count; c++)
            if (sim_chart_addr[c].addr != 0xFFFFu)
                sim_ram_read(sim_chart_addr[c].addr, (void *)el_charts[c].active, sim_chart_addr[c].size);
}

/* --trace-state: copy the devices' state fields from the MCU into the
 * host-side mirrors of el_host_state_items. */
static void mirror_states_from_mcu(void)
{
    uint16_t i;
    if (!el_host_trace_state)
        return;
    for (i = 0; i < sim_state_addr_count && i < el_host_state_item_count; i++)
        if (sim_state_addr[i].addr != 0xFFFFu)
            sim_ram_read(sim_state_addr[i].addr, (void *)el_host_state_items[i].addr, sim_state_addr[i].size);
}

uint64_t sim_tick_extend_bits(uint32_t tick, unsigned bits)
{
    static uint64_t last;
    uint32_t mask = bits >= 32u ? 0xFFFFFFFFu : ((uint32_t)1u << bits) - 1u;
    last += (uint32_t)(tick - (uint32_t)last) & mask;
    return last;
}

uint64_t sim_tick_extend(uint32_t tick)
{
    return sim_tick_extend_bits(tick, 32u);
}

/* The value the stimulus gave device datum sim_hw[k], to its chip model. */
static bool chip_value(uint16_t k)
{
    const el_item_t *it = &el_items[sim_hw[k].item];
    el_chip_value_t v;
    memset(&v, 0, sizeof v);
    switch (it->type) {
    case EL_T_BOOL: { uint8_t x; memcpy(&x, it->addr, 1); v.i = x; break; }
    case EL_T_I8: { int8_t x; memcpy(&x, it->addr, 1); v.i = x; break; }
    case EL_T_U8: { uint8_t x; memcpy(&x, it->addr, 1); v.i = x; break; }
    case EL_T_I16: { int16_t x; memcpy(&x, it->addr, 2); v.i = x; break; }
    case EL_T_U16: { uint16_t x; memcpy(&x, it->addr, 2); v.i = x; break; }
    case EL_T_I32: { int32_t x; memcpy(&x, it->addr, 4); v.i = x; break; }
    case EL_T_F32: { float x; memcpy(&x, it->addr, 4); v.is_float = true; v.f = x; break; }
    default: { uint32_t x; memcpy(&x, it->addr, 4); v.i = x; break; }
    }
    if (!v.is_float)
        v.f = (double)v.i;
    if (sim_chips_value(sim_hw[k].a, (uint8_t)sim_hw[k].b, &v))
        return true;
    el_host_error("%s: the stimulus at %llu us gives the chip model a value it refuses", it->name,
                  (unsigned long long)el_sim_now_us);
    return false;
}

void sim_instant_inputs(uint64_t tick)
{
    static unsigned char *before;
    static size_t before_size;
    size_t need = 0, off;
    uint16_t i, k;
    uint8_t d;

    el_sim_now_us = tick * (uint64_t)el_tick_us;
    if (sim_opt.has_duration && el_sim_now_us >= sim_opt.duration_us) {
        sim_stop = true;
        return;
    }
    if (sim_opt.stimulus == NULL)
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
            exit(SIM_EXIT_RUN);
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
            sim_ram_write(sim_item_addr[i].addr, it->addr, sim_item_addr[i].size);
        off += sim_item_addr[i].size;
    }
    /* Device `out` data: the hardware's state, then what the stimulus puts
     * there by now (host_stimulus.c's el_sim_read). A line camera compares
     * the new offset with the last one itself (a frame only on a change). */
    for (k = 0; k < sim_hw_count; k++) {
        const el_item_t *it = &el_items[sim_hw[k].item];
        if (it->kind == EL_K_DEV_OUT)
            memcpy(it->addr, sim_hw_state[k].value, sim_item_addr[sim_hw[k].item].size);
    }
    for (d = 0; d < el_device_count; d++)
        el_sim_read(d);
    for (k = 0; k < sim_hw_count; k++) {
        const el_item_t *it = &el_items[sim_hw[k].item];
        if (it->kind != EL_K_DEV_OUT)
            continue;
        if (sim_hw[k].kind != SIM_HW_CAMERA)
            memcpy(sim_hw_state[k].value, it->addr, sim_item_addr[sim_hw[k].item].size);
        if (sim_hw[k].kind == SIM_HW_CHIP ? !chip_value(k) : !sim_drive_hardware(k)) {
            sim_exit_status = SIM_EXIT_RUN;
            sim_stop = true;
            return;
        }
    }
}

void sim_instant_record(uint64_t tick)
{
    el_sim_now_us = tick * (uint64_t)el_tick_us;
    sim_instants++;
    if (sim_opt.trace == NULL)
        return;
    mirror_from_mcu(0xFu, true);
    mirror_states_from_mcu();
    el_host_trace_instant(tick);
}

uint8_t sim_quadrature(int64_t position)
{
    static const uint8_t ab[4] = {0u, 2u, 3u, 1u}; /* A << 1 | B: A leads B going forward */
    return ab[(uint64_t)position & 3u];
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

bool sim_pins_open(void)
{
    uint16_t k;
    bool pwm;
    pin_last = calloc(sim_pin_count ? sim_pin_count : 1u, sizeof *pin_last);
    if (pin_last == NULL)
        return false;
    for (k = 0; k < sim_pin_count; k++)
        pin_last[k] = -1;
    if (sim_opt.pins == NULL)
        return true;
    pins_out = fopen(sim_opt.pins, "w");
    if (pins_out == NULL) {
        el_host_error("cannot write %s: %s", sim_opt.pins, strerror(errno));
        return false;
    }
    {
        size_t n = strlen(sim_opt.pins);
        pins_vcd = n > 4u && strcasecmp(sim_opt.pins + n - 4u, ".vcd") == 0;
    }
    if (pins_vcd) {
        fprintf(pins_out, "$comment EasyLab pins of model %s on the %s $end\n$timescale 1ps $end\n"
                          "$scope module pins $end\n", el_model_name, sim_mcu);
        for (k = 0; k < sim_pin_count; k++) {
            const char *name = sim_pin_name(k, &pwm);
            fprintf(pins_out, "$var wire %d %c %s%s $end\n", pwm ? 8 : 1, pin_id(k), name, pwm ? "_pwm" : "");
        }
        fputs("$upscope $end\n$enddefinitions $end\n", pins_out);
    } else {
        fputs("cycle,time_us,pin,value\n", pins_out);
    }
    return true;
}

void sim_pin_record(uint16_t k, int value, uint64_t cycle)
{
    bool pwm;
    const char *name;
    if (pins_out == NULL || pin_last[k] == value)
        return;
    pin_last[k] = (int16_t)value;
    name = sim_pin_name(k, &pwm);
    if (pins_vcd) {
        /* Picoseconds: a cycle is a whole number of them at these clocks. */
        uint64_t t = cycle * (1000000000000u / sim_clock_hz);
        int b;
        if (t != pins_vcd_time) {
            fprintf(pins_out, "#%llu\n", (unsigned long long)t);
            pins_vcd_time = t;
        }
        if (pwm) {
            fputc('b', pins_out);
            for (b = 7; b >= 0; b--)
                fputc((value >> b) & 1 ? '1' : '0', pins_out);
            fprintf(pins_out, " %c\n", pin_id(k));
        } else {
            fprintf(pins_out, "%d%c\n", value & 1, pin_id(k));
        }
        return;
    }
    fprintf(pins_out, "%llu,%llu,%s%s,%d\n", (unsigned long long)cycle,
            (unsigned long long)(cycle * 1000000u / sim_clock_hz), name, pwm ? ".pwm" : "", value);
}

/* ---- the run ---- */

static uint64_t start_ns;
/* In real time the simulation runs at most PACE_AHEAD_NS ahead of the wall
 * clock and falls at most PACE_BEHIND_NS behind before its time goes on
 * from the wall clock's now: catching up further at full speed would show
 * a peer simulated time passing faster than its own (a remote host's 1 ms
 * deadline arriving a few hundred microseconds after the frame it answers,
 * when this process was held up for a few milliseconds). */
#define PACE_AHEAD_NS 200000u
#define PACE_BEHIND_NS 100000u
/* Behind by more than 50 ms and 2 % of the simulated time in all: said at
 * the end (a few stalls of a process on a shared machine are not news). */
#define PACE_REPORT_NS 50000000u
#define PACE_REPORT_PERCENT 2u
static uint64_t next_service;
static uint64_t behind_ns;    /* how far the simulation fell behind the wall clock, in all */

static void on_signal(int sig)
{
    (void)sig;
    sim_stop_signal = 1;
}

static uint64_t wall_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000000u + (uint64_t)ts.tv_nsec;
}

bool sim_start(uint8_t *eeprom)
{
    struct sigaction sa;
    sim_hw_state = calloc(sim_hw_count ? sim_hw_count : 1u, sizeof *sim_hw_state);
    if (sim_hw_state == NULL)
        return false;
    if ((sim_opt.stimulus != NULL && !el_host_stimulus_load(sim_opt.stimulus)) || !sim_nvram_load(eeprom))
        return false;
    if ((sim_opt.trace != NULL && !el_host_trace_open(sim_opt.trace)) || !sim_pins_open() || !sim_links_open())
        return false;
#if defined(__linux__)
    /* The pace's sleeps are tens of microseconds: without this the kernel
     * may stretch each by its default slack of 50 us. */
    (void)prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL);
#endif
    memset(&sa, 0, sizeof sa);
    sigemptyset(&sa.sa_mask);
    sa.sa_handler = on_signal;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    sa.sa_handler = SIG_IGN;
    sigaction(SIGPIPE, &sa, NULL);
    if (sim_opt.wait)
        sim_wait_for_clients();
    start_ns = wall_ns();
    return true;
}

bool sim_service(uint64_t cycle)
{
    int n;
    uint64_t us = cycle / (sim_clock_hz / 1000000u);
    if (cycle < next_service)
        return true;
    /* Every 100 us of simulated time, every 20 us in real time (a peer's
     * bytes reach the UART sooner: a remote-execution host's 1 ms deadlines). */
    next_service = cycle + sim_clock_hz / (sim_opt.fast ? 10000u : 50000u);
    /* A firmware without the simulation hooks never reaches T logically:
     * end a second of CPU time after T if no instant came at all. (One that
     * has instants gets there; a debugger may halt logical time for as
     * long as it likes, --halt from the start, as on the host board.) */
    if (sim_opt.has_duration && sim_instants == 0u && !sim_opt.halt && us > sim_opt.duration_us + 1000000u) {
        el_host_error("warning: no instant at or after %llu us came by %llu us of CPU time (a build without "
                      "--sim?): stopped", (unsigned long long)sim_opt.duration_us, (unsigned long long)us);
        return false;
    }
    for (n = 0; n < 4; n++)
        if (sim_links[n].mode == SIM_LINK_PTY || sim_links[n].mode == SIM_LINK_TCP)
            sim_link_service(&sim_links[n]);
    if (!sim_opt.fast) {
        /* At most PACE_AHEAD_NS ahead of the wall clock, and never
         * catching up at full speed after the harness was held up (a busy
         * machine): the simulated time then goes on from the wall clock's
         * now. A peer on a link (a remote-execution host within a deadline
         * of a few ms) never sees simulated time pass faster than its own. */
        uint64_t due = start_ns + cycle * 1000000000u / sim_clock_hz;
        uint64_t now = wall_ns();
        if (now > due + PACE_BEHIND_NS) {
            behind_ns += now - due;
            start_ns += now - due;
        }
        else if (due > now + PACE_AHEAD_NS) {
            struct timespec ts;
            ts.tv_sec = (time_t)((due - now) / 1000000000u);
            ts.tv_nsec = (long)((due - now) % 1000000000u);
            nanosleep(&ts, NULL);
        }
    }
    return true;
}

int sim_finish(uint64_t cycles, uint64_t asleep, const uint8_t *eeprom)
{
    int n;
    if (!el_host_trace_close())
        sim_exit_status = SIM_EXIT_RUN;
    if (pins_out != NULL && fclose(pins_out) != 0)
        sim_exit_status = SIM_EXIT_RUN;
    if (eeprom != NULL && !sim_nvram_save(eeprom))
        sim_exit_status = SIM_EXIT_RUN;
    if (!sim_opt.fast && behind_ns > PACE_REPORT_NS &&
        behind_ns * 100u > (uint64_t)el_sim_now_us * 1000u * PACE_REPORT_PERCENT) {
        /* In real time a peer (a master's round, a remote host) sees this
         * simulator's answers late: say so, with its pace. */
        uint64_t sim_ns = el_sim_now_us * 1000u;
        fprintf(stderr, "%s: the simulation fell %llu ms behind the wall clock in %llu ms of simulated time: this "
                        "machine ran it at %.2fx real time where it had to catch up, and its answers to its peers "
                        "came late by as much\n", el_host_prog, (unsigned long long)(behind_ns / 1000000u),
                (unsigned long long)(el_sim_now_us / 1000u),
                (double)sim_ns / (double)(sim_ns + behind_ns));
    }
    if (sim_opt.report)
        fprintf(stderr, "%s: cycles %llu (asleep %llu), instants %llu, time %llu us\n", el_host_prog,
                (unsigned long long)cycles, (unsigned long long)asleep, (unsigned long long)sim_instants,
                (unsigned long long)el_sim_now_us);
    for (n = 0; n < 4; n++) {
        if (sim_links[n].link_made)
            unlink(sim_links[n].arg);
        if (sim_links[n].fd >= 0)
            close(sim_links[n].fd);
    }
    el_host_stimulus_free();
    return sim_exit_status;
}
