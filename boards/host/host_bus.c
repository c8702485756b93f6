/* EasyLab host board: the master's side of a Modbus round's bus
 * (docs/distribution.md). One serial line per slave, named by the slave's
 * node: the environment variable EASYLAB_BUS_<node> gives its device (a
 * serial port, or the pty of the slave's UART in `easylab launch`), opened
 * raw at the first frame, which waits EASYLAB_BUS_SETTLE_MS (default 200)
 * for a slave started with the line. In real time, frames on one line are
 * at least EASYLAB_BUS_GAP_US (default 5000) apart (a silence from the end
 * of one, once it is out, to the start of the next), so that a slave whose
 * receiver ends frames at the t3.5 silence sees the sync and its slot as
 * two frames; in lock-step (--fast) every frame is answered, the sync too
 * (el_link.c). A slave that does not answer within EASYLAB_BUS_TIMEOUT_MS
 * (default 1000) is reported by name once; the round goes on with the
 * others. */
#include "host_internal.h"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#define BUS_LINES 16
#define EL_BUS_FRAME_MAX 256u /* an RTU frame */
#define FIRST_CONTACT_MS 250  /* lock-step: the first frame again until the slave is up */

typedef struct {
    const char *node;
    int fd;
    bool silent; /* reported */
    uint32_t unanswered; /* frames not sent, or sent without their answer */
    bool answered;       /* the slave has answered once */
    uint8_t last[EL_BUS_FRAME_MAX]; /* the last frame sent, for the first contact */
    uint16_t last_len;
    int64_t quiet_from_us; /* the end of the line's last frame, monotonic */
    bool settling;         /* the line is new: its first wait is the settle time */
    int64_t gap_us;        /* time this program's loop slept for the line's silences */
    int64_t answer_us;     /* time it waited for the slave's answers */
    uint32_t waits;        /* answers waited for */
} bus_line_t;

static int64_t first_frame_us = -1; /* the first frame after the settle: the blocked time's base */

static bus_line_t lines[BUS_LINES];
static uint8_t line_count;

bool el_port_bus_send(const char *node, const uint8_t *frame, uint16_t len);
uint16_t el_port_bus_receive(const char *node, uint8_t *buf, uint16_t want);
bool el_port_bus_lockstep(void);

/* Virtual time (--fast): each slave's sync is confirmed (el_link.c). */
bool el_port_bus_lockstep(void)
{
    return el_host_settings.fast;
}

static int64_t now_us(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000 + ts.tv_nsec / 1000;
}

static int64_t settle_us(void)
{
    const char *env = getenv("EASYLAB_BUS_SETTLE_MS");
    return (env != NULL ? atol(env) : 200) * 1000;
}

/* Wait until the line has been quiet for the gap. */
static void keep_gap(bus_line_t *line)
{
    const char *env = getenv("EASYLAB_BUS_GAP_US");
    /* lock-step: every frame is answered (the sync too), so frames cannot run together */
    int64_t gap = el_host_settings.fast ? 0 : env != NULL ? atol(env) : 5000;
    int64_t left = line->quiet_from_us + gap - now_us();
    if (left > 0) {
        struct timespec ts = {(time_t)(left / 1000000), (long)(left % 1000000) * 1000};
        while (nanosleep(&ts, &ts) != 0 && errno == EINTR) {
        }
    }
    if (line->settling) {
        /* The slave's start-up is not the run's time: the clock resumes
         * from here rather than owing the settle time to every instant. */
        line->settling = false;
        el_port_resync();
    } else if (left > 0) {
        line->gap_us += left;
    }
    if (first_frame_us < 0)
        first_frame_us = now_us();
}

static bus_line_t *line_of(const char *node)
{
    char name[96];
    const char *path;
    struct termios tio;
    bus_line_t *line;
    uint8_t i;
    for (i = 0u; i < line_count; i++) {
        if (strcmp(lines[i].node, node) == 0)
            return &lines[i];
    }
    if (line_count >= BUS_LINES)
        return NULL;
    line = &lines[line_count++];
    line->node = node;
    line->fd = -1;
    line->silent = false;
    line->unanswered = 0u;
    line->answered = false;
    line->last_len = 0u;
    line->quiet_from_us = 0;
    snprintf(name, sizeof name, "EASYLAB_BUS_%s", node);
    path = getenv(name);
    if (path == NULL) {
        fprintf(stderr, "easylab: no bus line to node '%s' (set %s)\n", node, name);
        return line;
    }
    line->fd = open(path, O_RDWR | O_NOCTTY);
    if (line->fd < 0) {
        fprintf(stderr, "easylab: cannot open the bus line to node '%s' (%s): %s\n", node, path, strerror(errno));
        return line;
    }
    if (tcgetattr(line->fd, &tio) == 0) {
        /* raw bytes: no line discipline, no echo, no translation */
        tio.c_iflag &= ~(tcflag_t)(IGNBRK | BRKINT | PARMRK | ISTRIP | INLCR | IGNCR | ICRNL | IXON);
        tio.c_oflag &= ~(tcflag_t)OPOST;
        tio.c_lflag &= ~(tcflag_t)(ECHO | ECHONL | ICANON | ISIG | IEXTEN);
        tio.c_cflag &= ~(tcflag_t)(CSIZE | PARENB);
        tio.c_cflag |= CS8;
        tio.c_cc[VMIN] = 1;
        tio.c_cc[VTIME] = 0;
        (void)tcsetattr(line->fd, TCSANOW, &tio);
    }
    /* a slave started with the line (a simulator waiting for its client)
     * gets the time to come up before the first frame */
    line->quiet_from_us = now_us() + settle_us();
    line->settling = true;
    line->gap_us = 0;
    line->answer_us = 0;
    return line;
}

static long timeout_ms(void)
{
    const char *env = getenv("EASYLAB_BUS_TIMEOUT_MS");
    return env != NULL ? atol(env) : 1000;
}

/* A frame that could not be sent or was not answered: counted, and the
 * slave named the first time. */
static void missed(bus_line_t *line)
{
    line->unanswered++;
    if (!line->silent) {
        line->silent = true;
        fprintf(stderr, "easylab: node '%s' is silent on the bus (no answer within %ld ms): its values are not "
                        "carried, the others go on\n", line->node, timeout_ms());
    }
}

bool el_port_bus_send(const char *node, const uint8_t *frame, uint16_t len)
{
    bus_line_t *line = line_of(node);
    uint16_t done = 0u;
    if (line == NULL)
        return false;
    if (line->fd < 0) {
        missed(line);
        return false;
    }
    keep_gap(line);
    (void)tcflush(line->fd, TCIFLUSH); /* a late answer to an earlier slot */
    if (len <= EL_BUS_FRAME_MAX) {
        memcpy(line->last, frame, len);
        line->last_len = len;
    }
    while (done < len) {
        ssize_t n = write(line->fd, frame + done, (size_t)(len - done));
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0) {
            missed(line);
            return false;
        }
        done = (uint16_t)(done + (uint16_t)n);
    }
    /* A serial port's write returns with the frame still going out: the
     * pause starts once it is out (a pty takes it at once). */
    (void)tcdrain(line->fd);
    line->quiet_from_us = now_us();
    return true;
}

static int64_t now_ms(void)
{
    return now_us() / 1000;
}

uint16_t el_port_bus_receive(const char *node, uint8_t *buf, uint16_t want)
{
    bus_line_t *line = line_of(node);
    int64_t end = now_ms() + timeout_ms();
    int64_t began = now_us();
    uint16_t got = 0u;
    if (line == NULL || line->fd < 0)
        return 0u;
    while (got < want) {
        struct pollfd p = {line->fd, POLLIN, 0};
        int64_t left = end - now_ms();
        /* Lock-step's first frame is the sync of round 0, which may be sent
         * again: a simulated slave may not listen yet when it first comes. */
        bool first_contact = el_host_settings.fast && !line->answered && got == 0u && line->last_len > 0u;
        int ready;
        ssize_t n;
        if (left <= 0)
            break;
        ready = poll(&p, 1, (int)(first_contact && left > FIRST_CONTACT_MS ? FIRST_CONTACT_MS : left));
        if (ready == 0 && first_contact) {
            if (write(line->fd, line->last, line->last_len) != (ssize_t)line->last_len)
                break;
            continue;
        }
        if (ready < 0 && errno == EINTR)
            continue;
        if (ready <= 0)
            break;
        n = read(line->fd, buf + got, (size_t)(want - got));
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0)
            break;
        got = (uint16_t)(got + (uint16_t)n);
    }
    line->quiet_from_us = now_us();
    line->answer_us += line->quiet_from_us - began;
    line->waits++;
    if (got < want)
        missed(line);
    else
        line->answered = true;
    return got;
}

/* Why a master's tasks were late, when they were: the share of the run
 * its loop spent blocked by the round (its silences, each slave's
 * answers), slave by slave. */
static void report_blocking(void)
{
    int64_t run_us = first_frame_us < 0 ? 0 : now_us() - first_frame_us;
    int64_t gaps = 0, blocked = 0;
    uint8_t i;
    bool late = false;
    for (i = 0u; i < el_task_count; i++)
        if (el_overruns[i] != 0u)
            late = true;
    if (!late || run_us <= 0 || el_host_settings.fast)
        return;
    for (i = 0u; i < line_count; i++) {
        gaps += lines[i].gap_us;
        blocked += lines[i].gap_us + lines[i].answer_us;
    }
    fprintf(stderr, "%s: bus: the round blocked this program's loop %lld ms of the %lld ms run (%lld %%): "
                    "%lld ms of silence before frames (EASYLAB_BUS_GAP_US)", el_host_prog, (long long)(blocked / 1000),
            (long long)(run_us / 1000), (long long)(100 * blocked / run_us), (long long)(gaps / 1000));
    for (i = 0u; i < line_count; i++)
        fprintf(stderr, ", %lld ms waiting for node '%s' (%lu answers, %.1f ms each)",
                (long long)(lines[i].answer_us / 1000), lines[i].node, (unsigned long)lines[i].waits,
                lines[i].waits ? (double)lines[i].answer_us / 1000.0 / (double)lines[i].waits : 0.0);
    fputs("; a task whose deadline falls in that time is late (docs/distribution.md, \"Real time\")\n", stderr);
}

void el_host_bus_report(void)
{
    uint8_t i;
    for (i = 0u; i < line_count; i++) {
        if (lines[i].unanswered != 0u)
            fprintf(stderr, "%s: bus: node '%s' left %lu frame(s) unanswered\n", el_host_prog, lines[i].node,
                    (unsigned long)lines[i].unanswered);
    }
    report_blocking();
}
