/* EasyLab remote execution: the proxy's runtime (see el_remote.h). */
#include "el_remote.h"

#if defined(EL_REMOTE_PROXY) && EL_REMOTE_PROXY

#include "el_crc16.h"
#include "el_debug_cobs.h"
#include "el_dispatch.h"
#include "el_model.h"
#include "el_port.h"
#include "el_remote_config.h" /* generated: the frame sizes of this device model */

#if !defined(EL_RMT_RX_FRAME) || !defined(EL_RMT_TX_FRAME) || !defined(EL_RMT_TASKS) || \
    EL_RMT_TASKS < 1u || EL_RMT_TASKS > 32u || EL_RMT_RX_FRAME > EL_RMT_MAX_FRAME || \
    EL_RMT_TX_FRAME > EL_RMT_MAX_FRAME || EL_RMT_RX_FRAME < EL_RMT_HEADER + EL_RMT_TRAILER + 1u || \
    EL_RMT_TX_FRAME < EL_RMT_HEADER + EL_RMT_TRAILER + 1u + 2u * (EL_RMT_COUNTER_COUNT + EL_RMT_TASKS)
#error "el_remote_config.h (easylab proxy) sizes the frames and tables: EL_RMT_RX_FRAME, EL_RMT_TX_FRAME, EL_RMT_TASKS"
#endif

#define TX_CAP (EL_COBS_MAX_ENCODED(EL_RMT_TX_FRAME) + 1u)
/* The largest payload the proxy sends. */
#define TX_PAYLOAD (EL_RMT_TX_FRAME - EL_RMT_HEADER - EL_RMT_TRAILER)

static uint8_t state = EL_RMT_STATE_SAFE;
static bool started; /* START came: UP frames flow (in the safe state too, telling the host) */
static uint8_t mode = EL_RMT_MODE_REAL_TIME;
static uint16_t counters[EL_RMT_COUNTER_COUNT];
static uint32_t last_frame_tick; /* the instant of the last valid frame (real time) */
static uint8_t overruns_in_a_row;

/* The current activation of each proxy task. */
static uint32_t release_tick[EL_RMT_TASKS];
static bool pending[EL_RMT_TASKS];  /* released, deadline not reached */
static bool arrived[EL_RMT_TASKS];  /* its values came (staged) */
static uint16_t task_overruns[EL_RMT_TASKS]; /* values that came late (COUNTERS' answer) */

/* The tasks released at the instant being processed. */
static uint32_t released_now;
static uint32_t released_tick;
static bool up_sent;
static bool down_done; /* lock-step: the DOWN of the instant being processed came */
static uint32_t polled_tick; /* the instant at whose wait (or processing) the link was last served */

/* A longer received frame is one the device model cannot produce: the
 * decoder drops it as oversize (counted malformed). */
static uint8_t rx_buf[EL_RMT_RX_FRAME];
static el_cobs_decoder_t rx;
static uint8_t frame[EL_RMT_TX_FRAME];
static uint8_t tx[TX_CAP];

static void put_u32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
    p[2] = (uint8_t)(v >> 16);
    p[3] = (uint8_t)(v >> 24);
}

static uint32_t get_u32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

static void count(uint8_t counter)
{
    if (counters[counter] < UINT16_MAX) {
        counters[counter]++;
    }
}

static void copy_bytes(uint8_t *dst, const uint8_t *src, uint16_t n)
{
    uint16_t i;
    for (i = 0u; i < n; i++) {
        dst[i] = src[i];
    }
}

/* Send frame[0 .. EL_RMT_HEADER + payload) with its CRC. */
static void send(uint8_t cmd, uint32_t instant, uint16_t payload)
{
    uint16_t n = (uint16_t)(EL_RMT_HEADER + payload);
    uint16_t crc, len;
    frame[0] = cmd;
    put_u32(&frame[1], instant);
    crc = el_crc16(frame, n);
    frame[n] = (uint8_t)crc;
    frame[n + 1u] = (uint8_t)(crc >> 8);
    len = el_cobs_encode(frame, (uint16_t)(n + EL_RMT_TRAILER), tx, (uint16_t)TX_CAP);
    if (len != 0u) {
        (void)el_remote_port_write(tx, len);
    }
}

static void apply_safe_values(void)
{
    uint16_t i, at = 0u;
    for (i = 0u; i < el_rmt_in_count; i++) {
        copy_bytes((uint8_t *)el_rmt_in_fields[i].addr, &el_rmt_safe[at], el_rmt_in_fields[i].size);
        at = (uint16_t)(at + el_rmt_in_fields[i].size);
    }
}

static void enter_safe_state(void)
{
    uint8_t t;
    apply_safe_values();
    state = EL_RMT_STATE_SAFE;
    for (t = 0u; t < EL_RMT_TASKS; t++) {
        arrived[t] = false;
    }
}

/* DOWN: the mask of the proxy tasks it carries, then their in data. */
static void on_down(uint32_t instant, const uint8_t *p, uint16_t n)
{
    uint32_t mask;
    uint16_t i, at = 0u, need = EL_RMT_DOWN_MASK, staged_at = 0u;
    if (n < EL_RMT_DOWN_MASK) {
        count(EL_RMT_COUNTER_MALFORMED);
        return;
    }
    mask = get_u32(p);
    for (i = 0u; i < el_rmt_in_count; i++) {
        if ((mask & ((uint32_t)1u << el_rmt_in_fields[i].owner)) != 0u) {
            need = (uint16_t)(need + el_rmt_in_fields[i].size);
        }
    }
    if (need != n) {
        count(EL_RMT_COUNTER_MALFORMED);
        return;
    }
    at = EL_RMT_DOWN_MASK;
    for (i = 0u; i < el_rmt_in_count; i++) {
        uint8_t task = el_rmt_in_fields[i].owner;
        uint16_t size = el_rmt_in_fields[i].size;
        if ((mask & ((uint32_t)1u << task)) != 0u) {
            if (pending[task] && release_tick[task] == instant) {
                copy_bytes(&el_rmt_staged[staged_at], &p[at], size);
                arrived[task] = true;
            }
            at = (uint16_t)(at + size);
        }
        staged_at = (uint16_t)(staged_at + size);
    }
    /* Tasks whose activation is over (or none): too late. The mask moves
     * one bit a turn: a shift by i is a loop of i steps on an 8-bit CPU. */
    for (i = 0u; mask != 0u; i++, mask >>= 1) {
        if ((mask & 1u) != 0u && (i >= EL_RMT_TASKS || !(pending[i] && release_tick[i] == instant))) {
            count(EL_RMT_COUNTER_STALE);
        }
    }
    if (instant == released_tick) {
        down_done = true;
    }
}

static void send_hello_answer(uint32_t instant)
{
    frame[EL_RMT_HEADER] = (uint8_t)EL_RMT_PROTOCOL_VERSION;
    put_u32(&frame[EL_RMT_HEADER + 1u], el_rmt_device_model_id);
    frame[EL_RMT_HEADER + 5u] = el_rmt_device_count_;
    frame[EL_RMT_HEADER + 6u] = state;
    send((uint8_t)(EL_RMT_CMD_HELLO | EL_RMT_RESPONSE), instant, EL_RMT_HELLO_ANSWER);
}

/* A damaged frame (bad CRC, malformed): counted; before START also answered
 * as HELLO is, so that a host that cannot frame the proxy's bytes (another
 * baud rate) sees them and says so, and one that can gets its answer. */
static void damaged(uint8_t counter)
{
    count(counter);
    if (!started) {
        send_hello_answer(0u);
    }
}

static void on_frame(uint16_t n)
{
    uint8_t cmd;
    uint32_t instant;
    uint16_t payload, i;
    const uint8_t *p = rx_buf + EL_RMT_HEADER;
    if (n < EL_RMT_HEADER + EL_RMT_TRAILER) {
        damaged(EL_RMT_COUNTER_MALFORMED);
        return;
    }
    if (el_crc16(rx_buf, n) != 0u) {
        damaged(EL_RMT_COUNTER_BAD_CRC);
        return;
    }
    count(EL_RMT_COUNTER_FRAMES);
    last_frame_tick = (uint32_t)el_now_tick();
    cmd = rx_buf[0];
    instant = get_u32(&rx_buf[1]);
    payload = (uint16_t)(n - EL_RMT_HEADER - EL_RMT_TRAILER);
    switch (cmd) {
    case EL_RMT_CMD_HELLO:
        send_hello_answer(instant);
        break;
    case EL_RMT_CMD_DEVICE: {
        const char *path;
        uint16_t len = 0u;
        if (payload != 1u || p[0] >= el_rmt_device_count_) {
            count(EL_RMT_COUNTER_MALFORMED);
            break;
        }
        path = el_rmt_device_paths[p[0]];
        frame[EL_RMT_HEADER] = p[0];
        put_u32(&frame[EL_RMT_HEADER + 1u], el_rmt_device_ids[p[0]]);
        while (path[len] != '\0' && len < TX_PAYLOAD - EL_RMT_DEVICE_ANSWER) {
            frame[EL_RMT_HEADER + EL_RMT_DEVICE_ANSWER + len] = (uint8_t)path[len];
            len++;
        }
        send((uint8_t)(cmd | EL_RMT_RESPONSE), instant, (uint16_t)(EL_RMT_DEVICE_ANSWER + len));
        break;
    }
    case EL_RMT_CMD_START:
        if (payload != 1u || (p[0] != EL_RMT_MODE_REAL_TIME && p[0] != EL_RMT_MODE_LOCK_STEP)) {
            count(EL_RMT_COUNTER_MALFORMED);
            break;
        }
        mode = p[0];
        state = EL_RMT_STATE_RUNNING;
        started = true;
        overruns_in_a_row = 0u;
        send((uint8_t)(cmd | EL_RMT_RESPONSE), instant, 0u);
        break;
    case EL_RMT_CMD_STOP:
        enter_safe_state();
        send((uint8_t)(cmd | EL_RMT_RESPONSE), instant, 0u);
        el_remote_port_end();
        break;
    case EL_RMT_CMD_COUNTERS: {
        /* the link's counters, then each proxy task's overruns (EL_RMT_TX_FRAME holds them) */
        uint8_t tasks = el_task_count < EL_RMT_TASKS ? el_task_count : (uint8_t)EL_RMT_TASKS;
        frame[EL_RMT_HEADER] = state;
        for (i = 0u; i < EL_RMT_COUNTER_COUNT + tasks; i++) {
            uint16_t v = i < EL_RMT_COUNTER_COUNT ? counters[i] : task_overruns[i - EL_RMT_COUNTER_COUNT];
            frame[EL_RMT_HEADER + 1u + 2u * i] = (uint8_t)v;
            frame[EL_RMT_HEADER + 2u + 2u * i] = (uint8_t)(v >> 8);
        }
        send((uint8_t)(cmd | EL_RMT_RESPONSE), instant, (uint16_t)(1u + 2u * (EL_RMT_COUNTER_COUNT + tasks)));
        break;
    }
    case EL_RMT_CMD_DOWN:
        if (state == EL_RMT_STATE_RUNNING) {
            on_down(instant, p, payload);
        }
        break;
    default:
        count(EL_RMT_COUNTER_MALFORMED);
        break;
    }
}

void el_remote_poll(void)
{
    uint8_t chunk[32];
    uint16_t got, i;
    polled_tick = (uint32_t)el_now_tick();
    while ((got = el_remote_port_read(chunk, (uint16_t)sizeof chunk)) != 0u) {
        for (i = 0u; i < got; i++) {
            uint8_t r = el_cobs_decode_byte(&rx, chunk[i]);
            if (r == EL_COBS_FRAME) {
                on_frame(rx.len);
            } else if (r == EL_COBS_OVERSIZE || r == EL_COBS_BAD) {
                damaged(EL_RMT_COUNTER_MALFORMED);
            }
        }
    }
}

void el_remote_boot(void)
{
    uint8_t t;
    /* A session starts from a known state whatever ran before (a fuzz
     * target boots one per input; a board's RAM is zeroed anyway). */
    state = EL_RMT_STATE_SAFE;
    started = false;
    mode = EL_RMT_MODE_REAL_TIME;
    for (t = 0u; t < EL_RMT_COUNTER_COUNT; t++) {
        counters[t] = 0u;
    }
    for (t = 0u; t < EL_RMT_TASKS; t++) {
        task_overruns[t] = 0u;
        pending[t] = false;
        arrived[t] = false;
    }
    last_frame_tick = 0u;
    overruns_in_a_row = 0u;
    released_now = 0u;
    polled_tick = 0u;
    up_sent = false;
    down_done = false;
    el_cobs_decoder_init(&rx, rx_buf, (uint16_t)sizeof rx_buf);
    apply_safe_values();
    /* The clock starts at START; a board that wants the run to end (the
     * host board: SIGTERM) ends it before, at the first tick. */
    while (state != EL_RMT_STATE_RUNNING && !el_remote_port_stopping()) {
        el_port_idle(50u);
    }
    el_port_resync(); /* tick 0 is due now, not when the board started (an MCU's timer runs from boot) */
}

/* An instant processed after its time (the proxy behind its clock: its
 * CPU late) has had no wait, so nothing served the link: serve it now,
 * before the instant's deadlines and releases, so that a DOWN that came is
 * applied and HELLO, COUNTERS and STOP are answered however late the
 * proxy runs. An instant that waited served it while it waited. */
static void serve_late(void)
{
    if (polled_tick != (uint32_t)el_now_tick()) {
        el_remote_poll();
    }
}

uint16_t el_remote_overruns(uint8_t task)
{
    return task < EL_RMT_TASKS ? task_overruns[task] : 0u;
}

/* Real time: no valid frame for the watchdog time means the host is gone.
 * (In lock-step the proxy's clock waits for the host instead.) */
static void watchdog(void)
{
    uint32_t now = (uint32_t)el_now_tick();
    if (state == EL_RMT_STATE_RUNNING && mode == EL_RMT_MODE_REAL_TIME &&
        (uint32_t)(now - last_frame_tick) >= el_rmt_watchdog_ticks) {
        count(EL_RMT_COUNTER_WATCHDOG);
        enter_safe_state();
    }
}

void el_remote_release(uint8_t task)
{
    uint32_t now = (uint32_t)el_now_tick();
    if (task >= EL_RMT_TASKS) { /* not a proxy task of this device model */
        return;
    }
    serve_late();
    watchdog();
    if (released_now == 0u || released_tick != now) {
        released_now = 0u;
        released_tick = now;
        up_sent = false;
        down_done = false;
    }
    released_now |= (uint32_t)1u << task;
    release_tick[task] = now;
    pending[task] = true;
    arrived[task] = false;
}

void el_remote_body(uint8_t task)
{
    uint16_t i, at = 0u;
    (void)task;
    if (up_sent || !started) {
        return;
    }
    up_sent = true;
    frame[EL_RMT_HEADER] = state; /* the host learns at once that the safe values hold */
    if (mode == EL_RMT_MODE_REAL_TIME && (el_wtick_t)(el_port_real_tick() - (el_wtick_t)released_tick) != 0u) {
        frame[EL_RMT_HEADER] |= (uint8_t)EL_RMT_STATE_BEHIND; /* this instant's tick has passed: the CPU is late */
    }
    at = EL_RMT_UP_STATE;
    for (i = 0u; i < el_rmt_out_count; i++) {
        const el_rmt_field_t *f = &el_rmt_out_fields[i];
        if ((el_rmt_device_readers[f->owner] & released_now) != 0u &&
            (uint16_t)(at + f->size) <= TX_PAYLOAD) { /* easylab proxy sized the frame to fit */
            copy_bytes(&frame[EL_RMT_HEADER + at], (const uint8_t *)f->addr, f->size);
            at = (uint16_t)(at + f->size);
        }
    }
    send(EL_RMT_CMD_UP, released_tick, at);
    while (mode == EL_RMT_MODE_LOCK_STEP && !down_done && state == EL_RMT_STATE_RUNNING &&
           !el_remote_port_stopping()) {
        el_port_idle(20u);
    }
}

/* Whether a proxy task drives device `in` data: a task that only reads
 * devices has no values coming, so it is never late. */
static bool drives_devices(uint8_t task)
{
    uint16_t i;
    for (i = 0u; i < el_rmt_in_count; i++) {
        if (el_rmt_in_fields[i].owner == task) {
            return true;
        }
    }
    return false;
}

void el_remote_publish(uint8_t task)
{
    uint16_t i, at = 0u;
    bool got;
    if (task >= EL_RMT_TASKS) { /* not a proxy task of this device model */
        return;
    }
    serve_late();
    got = arrived[task];
    watchdog();
    pending[task] = false;
    arrived[task] = false;
    if (state != EL_RMT_STATE_RUNNING) {
        return; /* the safe values stay */
    }
    if (!drives_devices(task)) {
        return; /* no values come for it: never late, and no break in a row of overruns */
    }
    if (!got) { /* an overrun: the host's values came late, the previous values stay */
        count(EL_RMT_COUNTER_OVERRUNS);
        if (task_overruns[task] < UINT16_MAX) { /* not el_overruns: the proxy's own lateness is another thing */
            task_overruns[task]++;
        }
        if (++overruns_in_a_row >= el_rmt_overrun_limit) {
            enter_safe_state();
        }
        return;
    }
    overruns_in_a_row = 0u;
    for (i = 0u; i < el_rmt_in_count; i++) {
        const el_rmt_field_t *f = &el_rmt_in_fields[i];
        if (f->owner == task) {
            copy_bytes((uint8_t *)f->addr, &el_rmt_staged[at], f->size);
        }
        at = (uint16_t)(at + f->size);
    }
}

void el_remote_shutdown(void)
{
    enter_safe_state();
}

#else
typedef int el_remote_not_a_proxy_t; /* ISO C: a translation unit declares something */
#endif
