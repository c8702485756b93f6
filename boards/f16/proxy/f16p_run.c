/* EasyLab f16 board, 16-bit proxy: the simulator of a simulation build
 * (`easylab build --board f16 --sim`), a host program.
 *
 *   NAME-sim [--fast] [--duration T] [--stimulus S.csv] [--trace T.csv|T.vcd]
 *            [--ihx FILE] [--timeout SECONDS] [--help]
 *
 * It runs the build's 8051 image (sdcc) in uCsim's s51 and takes the host
 * board's options where they mean the same, so that one stimulus gives one
 * trace on both: the stimulus is read with the host board's own code
 * (host_stimulus.c) and handed to the 8051 program as a stream of events,
 * each at the tick whose instant first reaches its time; the program
 * reports the bytes of every item and chart at every instant, and the trace
 * is written with the host board's own code (host_trace.c) from them, so
 * the files are the host board's byte for byte when the behaviour is the
 * same (proxy/f16p.h has the streams). --duration T ends the run at the
 * first instant whose time is >= T, which is not recorded (the host
 * board's rule); without it the run lasts until --timeout (default 600 s
 * of wall-clock time), an error. --fast is accepted: the simulation always
 * runs as fast as s51 can.
 *
 * Exit status as the host board's: 0 the run ended, 1 an error during it
 * (s51 failed, the program stopped early, a trace write failed), 2 a bad
 * command line or input file.
 */
#include "host_internal.h"

#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

/* The build's tables (generated f16p_run_model.c). */
extern const char f16p_ihx_default[];
extern const char f16p_s51[];
extern const char f16p_s51_cpu[];
extern const char f16p_s51_xtal[];
extern const char f16p_stack_note[];

#define EXIT_OK 0
#define EXIT_RUN 1
#define EXIT_USAGE 2
#define END_NONE 0xFFFFFFFFu

const char *el_host_prog = "easylab-f16-proxy";

uint64_t el_host_now_us(void)
{
    return 0u; /* the stimulus is replayed by the 8051 program, not here */
}

static struct {
    bool has_duration;
    uint64_t duration_us;
    const char *stimulus;
    const char *trace;
    const char *ihx;
    unsigned timeout_s;
} opt;

static void usage(FILE *f)
{
    fprintf(f,
            "usage: %s [--fast] [--duration T] [--stimulus FILE.csv] [--trace FILE.csv|FILE.vcd] [--ihx FILE]\n"
            "          [--timeout SECONDS] [--help]\n"
            "Runs model '%s' on the 16-bit proxy of the f16 board: its 8051 image (sdcc) in s51.\n"
            "  --duration T      end at the first instant at or after T (us, ms, s, m, h); needed to end\n"
            "  --stimulus FILE   device data, params and vars over time (the host board's format)\n"
            "  --trace FILE      the trace, CSV or VCD (the host board's formats)\n"
            "  --ihx FILE        the 8051 image (default %s)\n"
            "  --timeout S       wall-clock seconds before the run is stopped as an error (default 600)\n"
            "  --fast            accepted for the host board's command line (s51 always runs flat out)\n",
            el_host_prog, el_model_name, f16p_ihx_default);
}

static int parse_args(int argc, char **argv)
{
    int i;
    opt.ihx = f16p_ihx_default;
    opt.timeout_s = 600u;
    for (i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *why = NULL;
        if (strcmp(a, "--help") == 0) {
            usage(stdout);
            return EXIT_OK + 100;
        }
        if (strcmp(a, "--fast") == 0)
            continue;
        if (strcmp(a, "--duration") != 0 && strcmp(a, "--stimulus") != 0 && strcmp(a, "--trace") != 0 &&
            strcmp(a, "--ihx") != 0 && strcmp(a, "--timeout") != 0) {
            el_host_error("unknown option '%s' (--help lists them)", a);
            return EXIT_USAGE;
        }
        if (i + 1 >= argc) {
            el_host_error("%s: a value must follow", a);
            return EXIT_USAGE;
        }
        if (strcmp(a, "--duration") == 0) {
            if (!el_host_parse_duration(argv[++i], &opt.duration_us, &why)) {
                el_host_error("--duration %s: %s", argv[i], why);
                return EXIT_USAGE;
            }
            opt.has_duration = true;
        } else if (strcmp(a, "--stimulus") == 0) {
            opt.stimulus = argv[++i];
        } else if (strcmp(a, "--trace") == 0) {
            opt.trace = argv[++i];
        } else if (strcmp(a, "--ihx") == 0) {
            opt.ihx = argv[++i];
        } else {
            char *end;
            unsigned long s = strtoul(argv[++i], &end, 10);
            if (*end != '\0' || s == 0u || s > 86400u) {
                el_host_error("--timeout %s: give whole seconds, 1 .. 86400", argv[i]);
                return EXIT_USAGE;
            }
            opt.timeout_s = (unsigned)s;
        }
    }
    return EXIT_OK;
}

/* The first tick whose instant reaches `us`. */
static uint32_t tick_at(uint64_t us)
{
    uint64_t t = (us + el_tick_us - 1u) / el_tick_us;
    return t >= END_NONE ? END_NONE : (uint32_t)t;
}

static void put_le(FILE *f, uint32_t v, unsigned bytes)
{
    unsigned i;
    for (i = 0; i < bytes; i++)
        fputc((int)((v >> (8u * i)) & 0xFFu), f);
}

/* The input stream (proxy/f16p.h). */
static bool write_input(const char *path)
{
    FILE *f = fopen(path, "wb");
    size_t i;
    uint64_t time_us;
    uint16_t item, first, n;
    unsigned char value[8];
    if (f == NULL) {
        el_host_error("cannot write %s: %s", path, strerror(errno));
        return false;
    }
    fputs("EL16", f);
    put_le(f, opt.has_duration ? tick_at(opt.duration_us) : END_NONE, 4u);
    for (i = 0; opt.stimulus != NULL && el_host_stimulus_event(i, &time_us, &item, &first, &n, value); i++) {
        size_t size = el_host_type_size(el_items[item].type);
        fputc('e', f);
        put_le(f, tick_at(time_us), 4u);
        put_le(f, item, 2u);
        put_le(f, first, 2u);
        put_le(f, n, 2u);
        fputc((int)size, f);
        fwrite(value, 1, size, f);
    }
    if (fclose(f) != 0) {
        el_host_error("cannot write %s: %s", path, strerror(errno));
        return false;
    }
    return true;
}

static volatile sig_atomic_t timed_out;
static pid_t child;

static void on_alarm(int sig)
{
    (void)sig;
    timed_out = 1;
    if (child > 0)
        kill(child, SIGKILL);
}

/* s51's console: a watch on the top byte of the internal RAM, where the
 * 8051's stack ends, that stops the run at its second write (the start-up
 * code's clearing of the RAM is the first); run until the program stops
 * itself; quit. A stack that reaches the top would go on over the
 * registers at address 0 and give wrong values without a word. */
#define S51_COMMANDS "break iram w 0xff 2\nrun\nquit\n"
#define S51_STACK_TOP_EVENT "Event `write' at iram[0xff]"

/* s51 until the program stops the simulator; false (reported) otherwise. */
static bool run_s51(const char *in, const char *out, const char *commands, const char *log)
{
    char sif[4096];
    int status;
    struct sigaction sa;
    FILE *cmd = fopen(commands, "w");
    if (cmd == NULL || fputs(S51_COMMANDS, cmd) < 0 || fclose(cmd) != 0) {
        el_host_error("cannot write %s: %s", commands, strerror(errno));
        return false;
    }
    snprintf(sif, sizeof sif, "if=xram[0xffff],in=%s,out=%s", in, out);
    child = fork();
    if (child < 0) {
        el_host_error("cannot start %s: %s", f16p_s51, strerror(errno));
        return false;
    }
    if (child == 0) {
        FILE *l = freopen(log, "w", stdout);
        if (l == NULL || freopen(commands, "r", stdin) == NULL || dup2(fileno(stdout), 2) < 0)
            _exit(127);
        execlp(f16p_s51, f16p_s51, "-t", f16p_s51_cpu, "-X", f16p_s51_xtal, "-I", sif, opt.ihx, (char *)NULL);
        _exit(127);
    }
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_alarm;
    sigaction(SIGALRM, &sa, NULL);
    alarm(opt.timeout_s);
    while (waitpid(child, &status, 0) < 0 && errno == EINTR) {
    }
    alarm(0);
    if (timed_out) {
        el_host_error("the run did not end within %u s of wall-clock time (stopped); give --duration", opt.timeout_s);
        return false;
    }
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
        el_host_error("%s failed on %s (exit status %d): see %s", f16p_s51, opt.ihx,
                      WIFEXITED(status) ? WEXITSTATUS(status) : -1, log);
        return false;
    }
    return true;
}

static bool read_exact(FILE *f, void *dst, size_t n)
{
    return fread(dst, 1, n, f) == n;
}

/* The output stream into the trace; the number of instants, or -1. */
static long replay(const char *path)
{
    static const unsigned char head[] = {'E', 'L', '1', '6', 0x34, 0x12, 0x78, 0x56, 0x34, 0x12, 0x00, 0x00, 0xC0, 0x3F};
    unsigned char got[sizeof head];
    long instants = 0;
    FILE *f = fopen(path, "rb");
    int c;
    if (f == NULL || !read_exact(f, got, sizeof got) || memcmp(got, head, sizeof head) != 0) {
        el_host_error("%s: the proxy program wrote no report, or lays out its memory unlike this host", path);
        if (f != NULL)
            fclose(f);
        return -1;
    }
    while ((c = fgetc(f)) == 'I') {
        unsigned char t[4];
        uint16_t i;
        uint8_t k;
        bool ok = read_exact(f, t, 4u);
        for (i = 0; ok && i < el_item_count; i++)
            ok = read_exact(f, el_items[i].addr, el_host_type_size(el_items[i].type) * el_items[i].count);
        for (k = 0; ok && k < el_chart_count; k++)
            ok = read_exact(f, (void *)el_charts[k].active, el_charts[k].step_count);
        if (!ok)
            break;
        if (opt.trace != NULL)
            el_host_trace_instant((uint64_t)t[0] | (uint64_t)t[1] << 8 | (uint64_t)t[2] << 16 | (uint64_t)t[3] << 24);
        instants++;
    }
    fclose(f);
    if (c == head[0]) {
        /* its report's header again: the program jumped to its reset
         * vector, which a return into a stack overwritten past the top of
         * the internal RAM does (s51 does not stop it) */
        bool noted = f16p_stack_note[0] != '\0';
        el_host_error("the proxy program started again from its reset vector after %ld instants: its stack overflowed "
                      "the 8051's internal RAM, so the model does not fit the 16-bit proxy%s%s%s", instants,
                      noted ? " (" : "", f16p_stack_note, noted ? ")" : "");
        return -1;
    }
    if (c != 'X') {
        el_host_error("the proxy program stopped before the end of the run (after %ld instants)", instants);
        return -1;
    }
    return instants;
}

/* What s51 said when the program stopped early (its log's error lines). */
static void explain_stop(const char *log)
{
    char line[512];
    FILE *f = fopen(log, "r");
    while (f != NULL && fgets(line, sizeof line, f) != NULL) {
        if (strstr(line, S51_STACK_TOP_EVENT) != NULL)
            el_host_error("the program's stack reached the top of the 8051's internal RAM (s51 stopped it at a write "
                          "to iram[0xff]): the model does not fit the 16-bit proxy%s%s",
                          f16p_stack_note[0] != '\0' ? "; " : "", f16p_stack_note);
        else if (strstr(line, "Stack overflow") != NULL)
            el_host_error("s51: %s    (the 8051's stack, some 220 bytes of internal RAM, is too small for this "
                          "model's deepest call chain: it does not fit the 16-bit proxy)", strtok(line, "\r\n"));
        else if (strstr(line, "rroneous") != NULL || strstr(line, "nvalid") != NULL)
            el_host_error("s51: %s", strtok(line, "\r\n"));
    }
    if (f != NULL)
        fclose(f);
}

int main(int argc, char **argv)
{
    char dir[] = "/tmp/easylab-f16p-XXXXXX";
    char in[sizeof dir + 16], out[sizeof dir + 16], log[sizeof dir + 16], commands[sizeof dir + 16];
    int status = parse_args(argc, argv);
    long instants;
    if (status != EXIT_OK)
        return status == EXIT_OK + 100 ? EXIT_OK : status;
    if (opt.stimulus != NULL && !el_host_stimulus_load(opt.stimulus))
        return EXIT_USAGE;
    if (mkdtemp(dir) == NULL) {
        el_host_error("cannot make a folder in /tmp: %s", strerror(errno));
        return EXIT_RUN;
    }
    snprintf(in, sizeof in, "%s/in.bin", dir);
    snprintf(out, sizeof out, "%s/out.bin", dir);
    snprintf(log, sizeof log, "%s/s51.log", dir);
    snprintf(commands, sizeof commands, "%s/s51.cmd", dir);
    if (!write_input(in))
        return EXIT_RUN;
    if (opt.trace != NULL && !el_host_trace_open(opt.trace))
        return EXIT_USAGE;
    if (!run_s51(in, out, commands, log))
        return EXIT_RUN;
    instants = replay(out);
    if (instants < 0)
        explain_stop(log);
    if (!el_host_trace_close() || instants < 0)
        return EXIT_RUN;
    unlink(in);
    unlink(out);
    unlink(log);
    unlink(commands);
    rmdir(dir);
    el_host_stimulus_free();
    return EXIT_OK;
}
