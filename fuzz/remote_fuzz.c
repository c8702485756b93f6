/* libFuzzer target: the remote-execution proxy's frame decoding and
 * handling (runtime_c/el_remote.c, el_debug_cobs.c) under ASan and UBSan.
 *
 *   clang -g -O1 -fsanitize=fuzzer,address,undefined -DEL_REMOTE_PROXY=1 \
 *       [-DEL_FUZZ_LARGEST_FRAMES=1] -Ifuzz/remote_include -Iruntime_c \
 *       fuzz/remote_fuzz.c fuzz/remote_fuzz_model.c runtime_c/el_remote.c \
 *       runtime_c/el_debug_cobs.c runtime_c/el_crc16.c -o remote_fuzz
 *   ./remote_fuzz fuzz/remote_corpus -runs=150000
 *
 * The input is a sequence of records: a control byte, then (control & 0x7F)
 * bytes. Bit 7 clear: the bytes are a decoded frame without its CRC (cmd,
 * instant u32, payload), the instant counted from the proxy's current tick
 * (0: now); the target appends a valid CRC and COBS-encodes it, so the
 * fuzzer gets past the CRC check. Bit 7 set: the bytes go to the link raw
 * (garbage, cut frames, stray delimiters). The link hands them over in the
 * proxy's chunks (el_remote_port_read).
 *
 * The target boots a session per input (el_remote_boot, which waits for
 * START), then plays the dispatcher of fuzz/remote_fuzz_model.c: per record
 * one instant (publish, read, release, body: a lock-step body waits for its
 * DOWN, taking the next records). When the input ends it sends START if the
 * proxy still waits for it, then STOP, as `easylab remote` ends a run.
 *
 * Invariants checked (abort on violation): every frame the proxy sends is
 * one COBS frame with a valid CRC, at most EL_RMT_TX_FRAME bytes (the
 * size el_remote_config.h gives the model, fuzz/remote_include/), an
 * answer (response bit) or an UP for the current tick with the model's
 * payload size; after STOP the device `in` data hold their safe values.
 */
#include "el_remote.h"
#include "el_remote_config.h"
#include "el_crc16.h"
#include "el_debug_cobs.h"
#include "el_dispatch.h"
#include "el_port.h"
#include "fuzz_frames.h"

#include <stdlib.h>
#include <string.h>

void fuzz_model_reset(void);
bool fuzz_model_safe(void);
void fuzz_model_read(uint32_t tick);

#define UP_PAYLOAD 7u /* state, raw u16, window 2 x i16 */
#define WIRE_CAP (EL_COBS_MAX_ENCODED(EL_RMT_MAX_FRAME) + 2u)

static const uint8_t *input;
static size_t input_len, input_at;
static el_tick_t now;
static bool booting;  /* el_remote_boot waits for START */
static bool stopped;  /* STOP was answered: the board ends the run */

/* Bytes on their way to the proxy (el_remote_port_read takes them). */
static uint8_t link_buf[WIRE_CAP + 128u];
static uint16_t link_len, link_at;

static void put_u32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
    p[2] = (uint8_t)(v >> 16);
    p[3] = (uint8_t)(v >> 24);
}

/* Give the proxy `n` bytes, framed (CRC, COBS, delimiter) or raw. */
static void send_to_proxy(const uint8_t *bytes, uint16_t n, bool framed)
{
    uint8_t raw[EL_RMT_MAX_FRAME + 2u];
    uint16_t crc;
    link_len = 0u;
    link_at = 0u;
    if (!framed) {
        memcpy(link_buf, bytes, n);
        link_len = n;
    } else {
        memcpy(raw, bytes, n);
        if (n >= EL_RMT_HEADER) { /* the instant counts from now */
            uint32_t offset = (uint32_t)raw[1] | ((uint32_t)raw[2] << 8) | ((uint32_t)raw[3] << 16) |
                              ((uint32_t)raw[4] << 24);
            put_u32(&raw[1], (uint32_t)now + offset);
        }
        crc = el_crc16(raw, n);
        raw[n] = (uint8_t)crc;
        raw[n + 1u] = (uint8_t)(crc >> 8);
        link_len = el_cobs_encode(raw, (uint16_t)(n + 2u), link_buf, (uint16_t)(sizeof link_buf - 1u));
        if (link_len == 0u) {
            abort();
        }
        link_buf[link_len++] = 0u;
    }
    el_remote_poll();
    if (link_at != link_len) {
        abort(); /* the proxy takes every byte it is given */
    }
}

/* A frame of the host's own (after a 0x00 that ends whatever came before). */
static void send_command(uint8_t cmd, uint8_t payload_byte, uint16_t payload)
{
    static const uint8_t delimiter = 0u;
    uint8_t frame[EL_RMT_HEADER + 1u] = { 0u };
    frame[0] = cmd;
    frame[EL_RMT_HEADER] = payload_byte;
    send_to_proxy(&delimiter, 1u, false);
    send_to_proxy(frame, (uint16_t)(EL_RMT_HEADER + payload), true);
}

static void feed_record(void)
{
    uint8_t ctl = input[input_at++];
    uint8_t n = (uint8_t)(ctl & 0x7Fu);
    if (n > input_len - input_at) {
        n = (uint8_t)(input_len - input_at);
    }
    send_to_proxy(input + input_at, n, (ctl & 0x80u) == 0u);
    input_at += n;
}

/* ---- the board's side ---- */

el_tick_t el_now_tick(void)
{
    return now;
}

el_wtick_t el_port_real_tick(void)
{
    return (el_wtick_t)now; /* never behind: the target's clock is its instants */
}

void el_port_resync(void)
{
    /* The target's clock is its count of the dispatcher's instants: tick 0
     * is due when START has come, as a board's resync makes it. */
}

void el_port_idle(uint16_t max_ms)
{
    (void)max_ms;
    if (input_at < input_len && !stopped) {
        feed_record();
    } else if (booting) {
        send_command(EL_RMT_CMD_START, EL_RMT_MODE_REAL_TIME, 1u);
    } else {
        send_command(EL_RMT_CMD_STOP, 0u, 0u); /* ends a lock-step wait */
    }
}

uint16_t el_remote_port_read(uint8_t *buf, uint16_t max)
{
    uint16_t n = (uint16_t)(link_len - link_at);
    if (n > max) {
        n = max;
    }
    memcpy(buf, link_buf + link_at, n);
    link_at = (uint16_t)(link_at + n);
    return n;
}

bool el_remote_port_write(const uint8_t *frame, uint16_t len)
{
    uint8_t out[EL_RMT_TX_FRAME];
    uint16_t n = fuzz_sent_frame(frame, len, out, (uint16_t)sizeof out, EL_RMT_HEADER + EL_RMT_TRAILER);
    if (out[0] == EL_RMT_CMD_UP) {
        uint32_t instant = (uint32_t)out[1] | ((uint32_t)out[2] << 8) | ((uint32_t)out[3] << 16) |
                           ((uint32_t)out[4] << 24);
        if (instant != (uint32_t)now || n != EL_RMT_HEADER + UP_PAYLOAD + EL_RMT_TRAILER) {
            abort();
        }
    } else if ((out[0] & EL_RMT_RESPONSE) == 0u) {
        abort();
    }
    return true;
}

bool el_remote_port_stopping(void)
{
    return false; /* every session runs until STOP or the end of its input */
}

void el_remote_port_end(void)
{
    stopped = true;
    if (!fuzz_model_safe()) {
        abort(); /* STOP applies the safe values before it answers */
    }
}

/* ---- the dispatcher: one instant per record ---- */

static void instant(bool *pending)
{
    uint8_t task;
    for (task = 0u; task < 2u; task++) { /* deadlines: task 0 after 1 tick, task 1 after 2 */
        if (pending[task] && (task == 0u || ((uint32_t)now & 1u) == 0u)) {
            el_remote_publish(task);
            pending[task] = false;
        }
    }
    fuzz_model_read((uint32_t)now);
    for (task = 0u; task < 2u; task++) {
        if (task == 0u || ((uint32_t)now & 1u) == 0u) {
            el_remote_release(task);
            pending[task] = true;
        }
    }
    for (task = 0u; task < 2u && !stopped; task++) {
        if (pending[task] && (task == 0u || ((uint32_t)now & 1u) == 0u)) {
            el_remote_body(task);
        }
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    bool pending[2] = { false, false };
    input = data;
    input_len = size;
    input_at = 0u;
    now = 0u;
    stopped = false;
    link_len = 0u;
    link_at = 0u;
    fuzz_model_reset();
    booting = true;
    el_remote_boot();
    booting = false;
    while (input_at < input_len && !stopped) {
        instant(pending);
        if (input_at < input_len && !stopped) {
            feed_record();
        }
        now++;
    }
    if (!stopped) {
        send_command(EL_RMT_CMD_STOP, 0u, 0u);
    }
    el_remote_shutdown();
    if (!stopped || !fuzz_model_safe()) {
        abort();
    }
    return 0;
}
