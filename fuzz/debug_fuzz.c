/* libFuzzer target: the debug server's frame decoding and request dispatch
 * (runtime_c/el_debug.c, el_debug_cobs.c) under ASan and UBSan.
 *
 *   clang -g -O1 -fsanitize=fuzzer,address,undefined -DEL_DEBUG=1 \
 *       -Ifuzz/debug_include -Iruntime_c fuzz/debug_fuzz.c fuzz/debug_fuzz_model.c \
 *       runtime_c/el_debug.c runtime_c/el_debug_cobs.c runtime_c/el_crc16.c \
 *       -DEL_DEBUG_BOARD_COMMANDS=1 boards/host/host_load.c -o debug_fuzz
 *   ./debug_fuzz fuzz/debug_corpus -runs=150000
 *
 * The input is a sequence of records: a control byte, then (control & 0x7F)
 * bytes. Bit 7 clear: the bytes are a request (seq, cmd, payload); the
 * target appends a valid CRC, COBS-encodes it and feeds it, so the fuzzer
 * gets past the CRC check. Bit 7 set: the bytes go to the decoder raw
 * (garbage, cut frames, stray delimiters). After each record the target
 * plays the dispatcher: an instant (queued writes apply, halts), the
 * forced values and conditional breakpoints, a task, probes of every kind. A halted program is fed the following records
 * through el_port_idle, as a board would; when the input ends, the halt is
 * released (el_debug_abort_halt).
 *
 * With EL_DEBUG_BOARD_COMMANDS the board commands of local execution
 * (boards/host/host_load.c: a model text sent in pieces) are served too;
 * a committed text is taken and refused, as the interpreter would.
 *
 * Invariants checked (abort on violation): every response is one frame
 * that decodes, carries a valid CRC, is at most EL_DBG_MAX_FRAME bytes and
 * answers the request's sequence number with the response bit set.
 */
#include "el_debug.h"
#include "el_debug_cobs.h"
#include "el_crc16.h"
#include "fuzz_frames.h"

#include <stdlib.h>
#include <string.h>

void fuzz_model_reset(void);
#if defined(EL_DEBUG_BOARD_COMMANDS) && EL_DEBUG_BOARD_COMMANDS
uint32_t el_interp_take_load(const uint8_t **text);
void el_interp_load_result(uint8_t state, uint32_t program_id, const char *message);
#endif

static const uint8_t *input;
static size_t input_len, input_at;

static void feed_record(void)
{
    uint8_t ctl, n;
    uint8_t raw[EL_DBG_MAX_FRAME + 2u];
    uint8_t wire[EL_COBS_MAX_ENCODED(EL_DBG_MAX_FRAME + 2u) + 1u];
    uint16_t crc, len;
    ctl = input[input_at++];
    n = (uint8_t)(ctl & 0x7Fu);
    if (n > input_len - input_at) {
        n = (uint8_t)(input_len - input_at);
    }
    if ((ctl & 0x80u) != 0u) {
        el_debug_rx(input + input_at, n);
    } else {
        memcpy(raw, input + input_at, n);
        crc = el_crc16(raw, n);
        raw[n] = (uint8_t)(crc & 0xFFu);
        raw[n + 1u] = (uint8_t)(crc >> 8);
        len = el_cobs_encode(raw, (uint16_t)(n + 2u), wire, (uint16_t)sizeof wire);
        if (len == 0u) {
            abort();
        }
        el_debug_rx(wire, len);
    }
    input_at += n;
}

/* ---- the board's side ---- */

void el_port_idle(uint16_t max_ms)
{
    (void)max_ms;
    if (input_at < input_len) {
        feed_record();
    } else {
        el_debug_abort_halt = 1u;
    }
}

void el_port_resync(void)
{
}

uint16_t el_debug_port_read(uint8_t *buf, uint16_t max)
{
    (void)buf;
    (void)max;
    return 0u;
}

bool el_debug_port_write(const uint8_t *frame, uint16_t len)
{
    uint8_t out[EL_DBG_MAX_FRAME];
    (void)fuzz_sent_frame(frame, len, out, (uint16_t)sizeof out, 5u);
    if ((out[1] & EL_DBG_RESPONSE) == 0u) {
        abort();
    }
    return true;
}

bool el_debug_port_reset(uint8_t flags)
{
    (void)flags;
    return false;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    uint16_t k = 0u;
    input = data;
    input_len = size;
    input_at = 0u;
    el_debug_abort_halt = 0u;
    fuzz_model_reset();
    el_debug_boot();
    while (input_at < input_len) {
        feed_record();
        /* The dispatcher's and the model's hooks, as between instants. */
        el_debug_instant();
        EL_DEBUG_FORCE(); /* forced values; conditional breakpoints may halt here */
        el_debug_task_begin((uint8_t)(k % 3u));
        EL_DEBUG_PROBE(EL_DBG_P_CHART, 0u, 0u);
        EL_DEBUG_PROBE(EL_DBG_P_STEP, (uint16_t)(k % 2u), 1u);
        EL_DEBUG_PROBE(EL_DBG_P_TRANSITION, 1u, (uint16_t)(k % 3u));
        EL_DEBUG_PROBE_ACTOR(k % 3u);
        el_debug_task_end();
        el_debug_poll();
#if defined(EL_DEBUG_BOARD_COMMANDS) && EL_DEBUG_BOARD_COMMANDS
        {
            const uint8_t *text = NULL;
            uint32_t n = el_interp_take_load(&text);
            if (n != 0u && text == NULL) {
                abort();
            }
            if (n != 0u && (k & 1u) != 0u) {
                el_interp_load_result(EL_DBG_LOAD_REFUSED, 0u, (const char *)"refused by the fuzz target");
            }
        }
#endif
        k++;
    }
    /* Leave no breakpoint, halt request or queue for the next input. */
    el_debug_abort_halt = 1u;
    el_debug_instant();
    return 0;
}
