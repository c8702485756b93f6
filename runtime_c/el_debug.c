/* EasyLab runtime: the debug server (protocol: docs/protocol.md; hooks and
 * board contract: el_debug.h).
 *
 * Frames arrive as COBS-encoded bytes ending in 0x00. A decoded request is
 * seq, cmd, payload, CRC-16/MODBUS (low byte first) over seq, cmd and
 * payload; the response echoes seq, sets bit 7 of cmd and starts its
 * payload with a status byte. Every length and id from outside is checked
 * against the frame and the generated tables before use.
 *
 * Writes and transactions never touch the model between instants: they
 * queue and apply at the inputs step of the next instant (EL_DEBUG_INSTANT,
 * docs/ir.md step 2), all of a transaction at once. A program halted at an
 * instant is at that step, so there they apply at once.
 *
 * A halt loops on el_port_idle inside the probe that halted (logical time
 * stands still, the interfaces are served) and calls el_port_resync when
 * it ends, so real time resumes without catching up.
 */
#include "el_debug.h"

#if defined(EL_DEBUG_SERVER) && EL_DEBUG_SERVER

#include "el_debug_cobs.h"
#include "el_crc16.h"
#include "el_dispatch.h"
#include "el_model.h"
#include "el_port.h"


#if EL_DBG_MAX_PAYLOAD != EL_DBG_MAX_FRAME - EL_DBG_HEADER - EL_DBG_TRAILER
#error "el_debug_protocol.h: EL_DBG_MAX_PAYLOAD must be EL_DBG_MAX_FRAME - 4"
#endif

/* The sizes of this server (HELLO reports them): the model's (generated in
 * el_debug_config.h on boards short of RAM), else the protocol's largest. */
#ifndef EL_DBG_FRAME
#define EL_DBG_FRAME EL_DBG_MAX_FRAME
#endif
#ifndef EL_DBG_VALUE_BYTES
#define EL_DBG_VALUE_BYTES EL_DBG_VALUE_MAX
#endif
#ifndef EL_DBG_TX_ENTRIES
#define EL_DBG_TX_ENTRIES EL_DBG_TX_MAX
#endif
#ifndef EL_DBG_WRITE_ENTRIES
#define EL_DBG_WRITE_ENTRIES EL_DBG_WRITE_QUEUE
#endif
#ifndef EL_DBG_BP_SLOTS
#define EL_DBG_BP_SLOTS EL_DBG_BP_MAX
#endif
#if EL_DBG_FRAME > EL_DBG_MAX_FRAME || EL_DBG_VALUE_BYTES > EL_DBG_VALUE_MAX || \
    EL_DBG_TX_ENTRIES > EL_DBG_TX_MAX || EL_DBG_WRITE_ENTRIES > EL_DBG_WRITE_QUEUE || EL_DBG_BP_SLOTS > EL_DBG_BP_MAX
#error "el_debug_config.h: a size beyond the protocol's limits"
#endif

/* ---- state ----------------------------------------------------------------- */

typedef struct {
    uint16_t item;
    uint16_t elem;
    uint8_t op;                       /* EL_DBG_OP_... */
    uint8_t value[EL_DBG_VALUE_BYTES]; /* to write, or read when applied */
} entry_t;

typedef struct {
    uint8_t used;
    uint8_t kind;
    uint16_t a;
    uint16_t b;
    uint16_t hits;
} breakpoint_t;

#define TX_NONE 0u
#define TX_OPEN 1u
#define TX_COMMITTED 2u
#define TX_APPLIED 3u

static uint8_t rx_buf[EL_DBG_FRAME];
static el_cobs_decoder_t rx;
static bool rx_ready;
static uint8_t resp[EL_DBG_FRAME];
static uint16_t resp_len; /* bytes of resp in use (seq, cmd, status, payload) */
static bool resp_full;     /* a put did not fit: every later put of this response fails too */
static uint8_t wire[EL_COBS_MAX_ENCODED(EL_DBG_FRAME) + 1u];
static uint16_t wire_len; /* the last response as sent, for a repeated request */
static bool have_last;
static uint8_t last_seq;
static uint16_t last_crc;
static uint16_t counters[EL_DBG_C_COUNT];

static entry_t wq[EL_DBG_WRITE_ENTRIES];
static uint8_t wq_len;
static entry_t txq[EL_DBG_TX_ENTRIES];
static uint8_t tx_len;
static uint8_t tx_state;

static breakpoint_t bps[EL_DBG_BP_SLOTS];
static uint8_t bp_count;

uint8_t el_dbg_armed;
volatile uint8_t el_debug_abort_halt;
static bool halted;
static bool halt_request;
static uint8_t halt_why; /* EL_DBG_WHY_... of the current or next halt */
static uint8_t step_unit;
static uint8_t loc_kind;
static uint16_t loc_a = EL_DBG_NONE16;
static uint16_t loc_b = EL_DBG_NONE16;
static uint8_t loc_bp = EL_DBG_NONE8;
static uint8_t running_task = EL_DBG_NONE8;
static bool reset_pending;
static uint8_t reset_flags;

static void count(uint8_t which)
{
    if (counters[which] != UINT16_MAX) {
        counters[which]++;
    }
}

static void update_armed(void)
{
    el_dbg_armed = (uint8_t)((halt_request || step_unit != 0u || bp_count != 0u) && el_debug_abort_halt == 0u);
}

/* ---- little-endian fields --------------------------------------------------- */

static uint16_t get_u16(const uint8_t *p)
{
    return (uint16_t)((uint16_t)p[0] | (uint16_t)((uint16_t)p[1] << 8));
}

/* Byte copies of our own: the runtime needs no C library (some targets'
 * front ends have none). */
static void copy_bytes(void *dst, const void *src, uint16_t n)
{
    uint8_t *d = (uint8_t *)dst;
    const uint8_t *s = (const uint8_t *)src;
    while (n-- > 0u) {
        *d++ = *s++;
    }
}

static void zero_bytes(void *dst, uint16_t n)
{
    uint8_t *d = (uint8_t *)dst;
    while (n-- > 0u) {
        *d++ = 0u;
    }
}

static bool put_u8(uint8_t v)
{
    if (resp_full || resp_len + 1u > EL_DBG_FRAME - EL_DBG_TRAILER) {
        resp_full = true;
        return false;
    }
    resp[resp_len++] = v;
    return true;
}

static bool put_u16(uint16_t v)
{
    return put_u8((uint8_t)(v & 0xFFu)) && put_u8((uint8_t)(v >> 8));
}

static bool put_u32(uint32_t v)
{
    return put_u16((uint16_t)(v & 0xFFFFu)) && put_u16((uint16_t)(v >> 16));
}

/* ---- items --------------------------------------------------------------- */

static uint8_t type_size(uint8_t type)
{
    switch (type) {
    case EL_DBG_T_BOOL:
    case EL_DBG_T_I8:
    case EL_DBG_T_U8:
        return 1u;
    case EL_DBG_T_I16:
    case EL_DBG_T_U16:
        return 2u;
    case EL_DBG_T_I32:
    case EL_DBG_T_U32:
    case EL_DBG_T_F32:
    case EL_DBG_T_TIME:
        return 4u;
    default:
        return 0u;
    }
}

/* Element `elem` of an item as little-endian bytes (type_size of them). */
static void get_elem(const el_dbg_item_t *it, uint16_t elem, uint8_t *out)
{
    uint16_t v16;
    uint32_t v32;
    float f;
    switch (it->type) {
    case EL_DBG_T_BOOL:
        out[0] = ((const bool *)it->addr)[elem] ? 1u : 0u;
        break;
    case EL_DBG_T_I8:
    case EL_DBG_T_U8:
        out[0] = ((const uint8_t *)it->addr)[elem];
        break;
    case EL_DBG_T_I16:
    case EL_DBG_T_U16:
        v16 = ((const uint16_t *)it->addr)[elem];
        out[0] = (uint8_t)(v16 & 0xFFu);
        out[1] = (uint8_t)(v16 >> 8);
        break;
    case EL_DBG_T_F32:
        f = ((const float *)it->addr)[elem];
        copy_bytes(&v32, &f, (uint16_t)(sizeof v32));
        out[0] = (uint8_t)(v32 & 0xFFu);
        out[1] = (uint8_t)((v32 >> 8) & 0xFFu);
        out[2] = (uint8_t)((v32 >> 16) & 0xFFu);
        out[3] = (uint8_t)(v32 >> 24);
        break;
    default: /* 32-bit integers and time */
        v32 = ((const uint32_t *)it->addr)[elem];
        out[0] = (uint8_t)(v32 & 0xFFu);
        out[1] = (uint8_t)((v32 >> 8) & 0xFFu);
        out[2] = (uint8_t)((v32 >> 16) & 0xFFu);
        out[3] = (uint8_t)(v32 >> 24);
        break;
    }
}

static uint32_t le32(const uint8_t *in, uint8_t size)
{
    uint32_t v = 0u;
    uint8_t i;
    for (i = size; i > 0u; i--) {
        v = (v << 8) | in[i - 1u];
    }
    return v;
}

static void set_elem(const el_dbg_item_t *it, uint16_t elem, const uint8_t *in)
{
    uint32_t v32 = le32(in, type_size(it->type));
    float f;
    switch (it->type) {
    case EL_DBG_T_BOOL:
        ((bool *)it->addr)[elem] = in[0] != 0u;
        break;
    case EL_DBG_T_I8:
    case EL_DBG_T_U8:
        ((uint8_t *)it->addr)[elem] = in[0];
        break;
    case EL_DBG_T_I16:
    case EL_DBG_T_U16:
        ((uint16_t *)it->addr)[elem] = (uint16_t)v32;
        break;
    case EL_DBG_T_F32:
        copy_bytes(&f, &v32, (uint16_t)(sizeof f));
        ((float *)it->addr)[elem] = f;
        break;
    default:
        ((uint32_t *)it->addr)[elem] = v32;
        break;
    }
}

/* Is `in` (type_size bytes) an acceptable value of the item? */
static uint8_t check_value(const el_dbg_item_t *it, const uint8_t *in)
{
    uint8_t size = type_size(it->type);
    uint32_t u = le32(in, size);
    int32_t s;
    const el_dbg_range_t *r;
    float f;
    if (it->type == EL_DBG_T_BOOL && in[0] > 1u) {
        return EL_DBG_E_VALUE;
    }
    if ((it->flags & EL_DBG_F_RANGE) == 0u || it->range == EL_DBG_NONE16) {
        return EL_DBG_OK;
    }
    r = &el_dbg_ranges[it->range];
    switch (it->type) {
    case EL_DBG_T_I8:
        s = (int32_t)(int8_t)(uint8_t)u;
        break;
    case EL_DBG_T_I16:
        s = (int32_t)(int16_t)(uint16_t)u;
        break;
    case EL_DBG_T_I32:
        s = u > 0x7FFFFFFFuL ? -(int32_t)(0xFFFFFFFFuL - u) - 1 : (int32_t)u;
        break;
    case EL_DBG_T_F32:
        copy_bytes(&f, &u, (uint16_t)(sizeof f));
        return (f >= r->lo.f && f <= r->hi.f) ? EL_DBG_OK : EL_DBG_E_RANGE;
    default: /* unsigned, time, bool */
        return (u >= r->lo.u && u <= r->hi.u) ? EL_DBG_OK : EL_DBG_E_RANGE;
    }
    return (s >= r->lo.i && s <= r->hi.i) ? EL_DBG_OK : EL_DBG_E_RANGE;
}

static void apply(entry_t *e)
{
    const el_dbg_item_t *it = &el_dbg_items[e->item];
    if (e->op == EL_DBG_OP_WRITE) {
        set_elem(it, e->elem, e->value);
    } else {
        get_elem(it, e->elem, e->value);
    }
}

static bool at_instant(void)
{
    return halted && loc_kind == EL_DBG_P_INSTANT;
}

/* The queued writes, then a committed transaction: at an instant's inputs. */
static void apply_queues(void)
{
    uint8_t i;
    for (i = 0u; i < wq_len; i++) {
        apply(&wq[i]);
    }
    wq_len = 0u;
    if (tx_state == TX_COMMITTED) {
        for (i = 0u; i < tx_len; i++) {
            apply(&txq[i]);
        }
        tx_state = TX_APPLIED;
    }
}

/* ---- halting ---------------------------------------------------------------- */

static void halt_here(uint8_t why, uint8_t kind, uint16_t a, uint16_t b, uint8_t bp)
{
    halted = true;
    halt_why = why;
    halt_request = false;
    step_unit = 0u;
    loc_kind = kind;
    loc_a = a;
    loc_b = b;
    loc_bp = bp;
    update_armed();
    while (halted && el_debug_abort_halt == 0u) {
        el_port_idle(EL_DBG_IDLE_MS);
    }
    halted = false;
    halt_why = EL_DBG_WHY_NONE;
    loc_kind = EL_DBG_P_NONE;
    loc_a = loc_b = EL_DBG_NONE16;
    loc_bp = EL_DBG_NONE8;
    if (el_debug_abort_halt != 0u) {
        halt_request = false;
        step_unit = 0u;
        bp_count = 0u;
        zero_bytes(bps, (uint16_t)(sizeof bps));
    }
    update_armed();
    el_port_resync();
}

void el_debug_probe(uint8_t kind, uint16_t a, uint16_t b)
{
    uint8_t i;
    if (el_debug_abort_halt != 0u || halted) {
        return;
    }
    for (i = 0u; i < EL_DBG_BP_SLOTS; i++) {
        breakpoint_t *bp = &bps[i];
        if (bp->used != 0u && bp->kind == kind && bp->a == a && bp->b == b) {
            if (bp->hits != UINT16_MAX) {
                bp->hits++;
            }
            halt_here(EL_DBG_WHY_BREAKPOINT, kind, a, b, i);
            return;
        }
    }
    if (step_unit == kind) {
        halt_here(EL_DBG_WHY_STEP, kind, a, b, EL_DBG_NONE8);
    } else if (halt_request && kind == EL_DBG_P_INSTANT) {
        halt_here(halt_why == EL_DBG_WHY_START ? EL_DBG_WHY_START : EL_DBG_WHY_BREAK, kind, a, b, EL_DBG_NONE8);
    }
}

void el_debug_probe_actor(const void *self)
{
    uint16_t i;
    for (i = 0u; i < el_dbg_actor_count; i++) {
        if (el_dbg_actors[i] == self) {
            el_debug_probe(EL_DBG_P_ACTOR, i, 0u);
            return;
        }
    }
}

void el_debug_instant(void)
{
    /* Serve the host once per instant even when the board's wait leaves
     * no idle time (a real-time tick of 1 ms or less): bounded work. */
    el_debug_poll();
    apply_queues();
    if (el_dbg_armed != 0u) {
        el_debug_probe(EL_DBG_P_INSTANT, 0u, 0u);
    }
}

void el_debug_task_begin(uint8_t task)
{
    running_task = task;
    if (el_dbg_armed != 0u) {
        el_debug_probe(EL_DBG_P_TASK, task, 0u);
    }
}

void el_debug_task_end(void)
{
    running_task = EL_DBG_NONE8;
}

void el_debug_halt_at_start(void)
{
    halt_request = true;
    halt_why = EL_DBG_WHY_START;
    update_armed();
}

/* ---- requests ----------------------------------------------------------------- */

/* Is (kind, a, b) a probe point of this program? */
static bool valid_point(uint8_t kind, uint16_t a, uint16_t b)
{
    switch (kind) {
    case EL_DBG_P_INSTANT:
        return a == 0u && b == 0u;
    case EL_DBG_P_TASK:
        return a < el_task_count && b == 0u;
    case EL_DBG_P_CHART:
        return a < el_dbg_chart_count && b == 0u;
    case EL_DBG_P_STEP:
        return a < el_dbg_chart_count && b < el_dbg_charts[a].step_count;
    case EL_DBG_P_TRANSITION:
        return a < el_dbg_chart_count && b < el_dbg_charts[a].transition_count;
    case EL_DBG_P_ACTOR:
        return a < el_dbg_actor_count && b == 0u;
    default:
        return false;
    }
}

static uint8_t status_flags(void)
{
    uint8_t f = 0u;
    if (halted) {
        f |= EL_DBG_S_HALTED;
    }
    if (tx_state == TX_OPEN) {
        f |= EL_DBG_S_TX_OPEN;
    } else if (tx_state == TX_COMMITTED) {
        f |= EL_DBG_S_TX_COMMITTED;
    } else if (tx_state == TX_APPLIED) {
        f |= EL_DBG_S_TX_APPLIED;
    }
    if (wq_len != 0u) {
        f |= EL_DBG_S_WRITES_PENDING;
    }
    if (halt_request || step_unit != 0u) {
        f |= EL_DBG_S_HALT_PENDING;
    }
    return f;
}

static bool put_location(void)
{
    return put_u8(halted ? 1u : 0u) && put_u8(halt_why) && put_u8(loc_kind) && put_u16(loc_a) && put_u16(loc_b)
        && put_u8(loc_bp);
}

/* The values of the applied transaction's reads. */
static uint8_t put_tx_reads(void)
{
    uint8_t i, k;
    for (i = 0u; i < tx_len; i++) {
        if (txq[i].op == EL_DBG_OP_READ) {
            uint8_t size = type_size(el_dbg_items[txq[i].item].type);
            for (k = 0u; k < size; k++) {
                if (!put_u8(txq[i].value[k])) {
                    return EL_DBG_E_TOO_BIG;
                }
            }
        }
    }
    return EL_DBG_OK;
}

static uint8_t do_read(const uint8_t *p, uint16_t n)
{
    uint16_t k, e;
    if (n == 0u || (n & 1u) != 0u) {
        return EL_DBG_E_LENGTH;
    }
    for (k = 0u; k < n; k += 2u) {
        if (get_u16(p + k) >= el_dbg_item_count) {
            return EL_DBG_E_ID;
        }
    }
    if (tx_state == TX_OPEN) {
        /* Queued: one entry per element, values come with the commit. */
        uint16_t needed = 0u;
        for (k = 0u; k < n; k += 2u) {
            needed = (uint16_t)(needed + el_dbg_items[get_u16(p + k)].count);
            if (needed > EL_DBG_TX_ENTRIES) {
                return EL_DBG_E_QUEUE_FULL;
            }
        }
        if ((uint16_t)(tx_len + needed) > EL_DBG_TX_ENTRIES) {
            return EL_DBG_E_QUEUE_FULL;
        }
        (void)put_u8(EL_DBG_QUEUED);
        (void)put_u8(tx_len);
        for (k = 0u; k < n; k += 2u) {
            uint16_t id = get_u16(p + k);
            for (e = 0u; e < el_dbg_items[id].count; e++) {
                txq[tx_len].item = id;
                txq[tx_len].elem = e;
                txq[tx_len].op = EL_DBG_OP_READ;
                tx_len++;
            }
        }
        return EL_DBG_OK;
    }
    for (k = 0u; k < n; k += 2u) {
        const el_dbg_item_t *it = &el_dbg_items[get_u16(p + k)];
        uint8_t size = type_size(it->type);
        if ((uint32_t)resp_len + (uint32_t)it->count * size > (uint32_t)(EL_DBG_FRAME - EL_DBG_TRAILER)) {
            return EL_DBG_E_TOO_BIG;
        }
        for (e = 0u; e < it->count; e++) {
            get_elem(it, e, resp + resp_len);
            resp_len = (uint16_t)(resp_len + size);
        }
    }
    return EL_DBG_OK;
}

static uint8_t do_write(const uint8_t *p, uint16_t n)
{
    uint16_t id, elem;
    const el_dbg_item_t *it;
    uint8_t size, st;
    entry_t *e;
    if (n < 5u) {
        return EL_DBG_E_LENGTH;
    }
    id = get_u16(p);
    elem = get_u16(p + 2);
    if (id >= el_dbg_item_count) {
        return EL_DBG_E_ID;
    }
    it = &el_dbg_items[id];
    size = type_size(it->type);
    if (n != 4u + size) {
        return EL_DBG_E_LENGTH;
    }
    if ((it->flags & EL_DBG_F_WRITE) == 0u) {
        return EL_DBG_E_READ_ONLY;
    }
    if (elem >= it->count) {
        return EL_DBG_E_VALUE;
    }
    st = check_value(it, p + 4);
    if (st != EL_DBG_OK) {
        return st;
    }
    if (tx_state == TX_OPEN) {
        if (tx_len >= EL_DBG_TX_ENTRIES) {
            return EL_DBG_E_QUEUE_FULL;
        }
        e = &txq[tx_len];
    } else {
        if (wq_len >= EL_DBG_WRITE_ENTRIES) {
            return EL_DBG_E_QUEUE_FULL;
        }
        e = &wq[wq_len];
    }
    e->item = id;
    e->elem = elem;
    e->op = EL_DBG_OP_WRITE;
    zero_bytes(e->value, (uint16_t)(sizeof e->value));
    copy_bytes(e->value, p + 4, (uint16_t)(size));
    if (tx_state == TX_OPEN) {
        (void)put_u8(EL_DBG_QUEUED);
        (void)put_u8(tx_len);
        tx_len++;
    } else if (at_instant()) {
        apply(e);
        (void)put_u8(EL_DBG_APPLIED);
    } else {
        wq_len++;
        (void)put_u8(EL_DBG_QUEUED);
    }
    return EL_DBG_OK;
}

static uint8_t do_commit(void)
{
    if (tx_state != TX_OPEN) {
        return EL_DBG_E_NO_TX;
    }
    tx_state = TX_COMMITTED;
    if (at_instant()) {
        apply_queues();
        (void)put_u8(EL_DBG_APPLIED);
        return put_tx_reads();
    }
    (void)put_u8(EL_DBG_QUEUED);
    return EL_DBG_OK;
}

static uint8_t do_bp_set(const uint8_t *p, uint16_t n)
{
    uint8_t kind, i;
    uint16_t a, b;
    if (n != 5u) {
        return EL_DBG_E_LENGTH;
    }
    kind = p[0];
    a = get_u16(p + 1);
    b = get_u16(p + 3);
    if (!valid_point(kind, a, b)) {
        return EL_DBG_E_ID;
    }
    for (i = 0u; i < EL_DBG_BP_SLOTS; i++) {
        if (bps[i].used != 0u && bps[i].kind == kind && bps[i].a == a && bps[i].b == b) {
            (void)put_u8(i); /* already set: the same slot */
            return EL_DBG_OK;
        }
    }
    for (i = 0u; i < EL_DBG_BP_SLOTS; i++) {
        if (bps[i].used == 0u) {
            bps[i].used = 1u;
            bps[i].kind = kind;
            bps[i].a = a;
            bps[i].b = b;
            bps[i].hits = 0u;
            bp_count++;
            update_armed();
            (void)put_u8(i);
            return EL_DBG_OK;
        }
    }
    return EL_DBG_E_BP_FULL;
}

static uint8_t do_bp_clear(const uint8_t *p, uint16_t n)
{
    if (n != 1u) {
        return EL_DBG_E_LENGTH;
    }
    if (p[0] == EL_DBG_NONE8) {
        zero_bytes(bps, (uint16_t)(sizeof bps));
        bp_count = 0u;
    } else if (p[0] >= EL_DBG_BP_SLOTS || bps[p[0]].used == 0u) {
        return EL_DBG_E_ID;
    } else {
        bps[p[0]].used = 0u;
        bp_count--;
    }
    update_armed();
    return EL_DBG_OK;
}

static uint8_t do_stack(void)
{
    uint8_t c, s;
    bool ok = put_u32((uint32_t)el_now_tick()) && put_location() && put_u8(running_task)
        && put_u16(halted && loc_kind == EL_DBG_P_ACTOR ? loc_a : EL_DBG_NONE16) && put_u8(el_dbg_chart_count);
    for (c = 0u; ok && c < el_dbg_chart_count; c++) {
        ok = put_u8(el_dbg_charts[c].slot_count);
        for (s = 0u; ok && s < el_dbg_charts[c].slot_count; s++) {
            ok = put_u8(el_dbg_charts[c].slots[s]);
        }
    }
    return ok ? EL_DBG_OK : EL_DBG_E_TOO_BIG;
}

/* Run one request (cmd, payload p[n]); the response's status byte is at
 * resp[2], its payload follows. Returns the status. */
static uint8_t dispatch(uint8_t cmd, const uint8_t *p, uint16_t n)
{
    uint8_t i;
    switch (cmd) {
    case EL_DBG_CMD_HELLO:
        if (n != 0u) {
            return EL_DBG_E_LENGTH;
        }
        (void)put_u8(EL_DBG_PROTOCOL_VERSION);
        (void)put_u16(EL_DBG_FRAME);
        (void)put_u8(EL_DBG_WINDOW);
        (void)put_u32(el_program_id);
        (void)put_u16(el_dbg_item_count);
        (void)put_u16(el_dbg_actor_count);
        (void)put_u8(el_dbg_chart_count);
        (void)put_u8(el_task_count);
        (void)put_u8(EL_DBG_TX_ENTRIES);
        (void)put_u8(EL_DBG_WRITE_ENTRIES);
        (void)put_u8(EL_DBG_BP_SLOTS);
        (void)put_u8(EL_DBG_VALUE_MAX);
        return EL_DBG_OK;
    case EL_DBG_CMD_GET_PROGRAM_ID:
        if (n != 0u) {
            return EL_DBG_E_LENGTH;
        }
        (void)put_u32(el_program_id);
        return EL_DBG_OK;
    case EL_DBG_CMD_GET_FLAGS:
        if (n != 0u) {
            return EL_DBG_E_LENGTH;
        }
        (void)put_u8(status_flags());
        (void)put_location();
        (void)put_u32((uint32_t)el_now_tick());
        (void)put_u8(wq_len);
        (void)put_u8(tx_len);
        return EL_DBG_OK;
    case EL_DBG_CMD_GET_COUNTERS:
        if (n != 0u) {
            return EL_DBG_E_LENGTH;
        }
        (void)put_u8(EL_DBG_C_COUNT);
        for (i = 0u; i < EL_DBG_C_COUNT; i++) {
            (void)put_u16(counters[i]);
        }
        return EL_DBG_OK;
    case EL_DBG_CMD_ITEM_INFO: {
        const el_dbg_item_t *it;
        uint8_t lo[4], hi[4];
        if (n != 2u) {
            return EL_DBG_E_LENGTH;
        }
        if (get_u16(p) >= el_dbg_item_count) {
            return EL_DBG_E_ID;
        }
        it = &el_dbg_items[get_u16(p)];
        zero_bytes(lo, (uint16_t)(sizeof lo));
        zero_bytes(hi, (uint16_t)(sizeof hi));
        if ((it->flags & EL_DBG_F_RANGE) != 0u && it->range != EL_DBG_NONE16) {
            uint32_t l, h;
            copy_bytes(&l, &el_dbg_ranges[it->range].lo, (uint16_t)(sizeof l));
            copy_bytes(&h, &el_dbg_ranges[it->range].hi, (uint16_t)(sizeof h));
            for (i = 0u; i < 4u; i++) {
                lo[i] = (uint8_t)((l >> (8u * i)) & 0xFFu);
                hi[i] = (uint8_t)((h >> (8u * i)) & 0xFFu);
            }
        }
        (void)put_u8(it->type);
        (void)put_u8(it->kind);
        (void)put_u8(it->flags);
        (void)put_u16(it->count);
        for (i = 0u; i < 4u; i++) {
            (void)put_u8(lo[i]);
        }
        for (i = 0u; i < 4u; i++) {
            (void)put_u8(hi[i]);
        }
        return EL_DBG_OK;
    }
    case EL_DBG_CMD_READ:
        return do_read(p, n);
    case EL_DBG_CMD_WRITE:
        return do_write(p, n);
    case EL_DBG_CMD_TX_BEGIN:
        if (n != 0u) {
            return EL_DBG_E_LENGTH;
        }
        if (tx_state == TX_OPEN || tx_state == TX_COMMITTED) {
            return EL_DBG_E_TX_BUSY;
        }
        tx_state = TX_OPEN;
        tx_len = 0u;
        return EL_DBG_OK;
    case EL_DBG_CMD_TX_COMMIT:
        return n != 0u ? EL_DBG_E_LENGTH : do_commit();
    case EL_DBG_CMD_TX_ABORT:
        if (n != 0u) {
            return EL_DBG_E_LENGTH;
        }
        if (tx_state != TX_OPEN && tx_state != TX_COMMITTED) {
            return EL_DBG_E_NO_TX;
        }
        tx_state = TX_NONE;
        tx_len = 0u;
        return EL_DBG_OK;
    case EL_DBG_CMD_TX_RESULT:
        if (n != 0u) {
            return EL_DBG_E_LENGTH;
        }
        (void)put_u8(tx_state == TX_OPEN ? 1u : tx_state == TX_COMMITTED ? 2u : tx_state == TX_APPLIED ? 3u : 0u);
        return tx_state == TX_APPLIED ? put_tx_reads() : EL_DBG_OK;
    case EL_DBG_CMD_GET_STACK:
        return n != 0u ? EL_DBG_E_LENGTH : do_stack();
    case EL_DBG_CMD_RUN:
        if (n != 0u) {
            return EL_DBG_E_LENGTH;
        }
        halt_request = false;
        step_unit = 0u;
        halted = false;
        update_armed();
        return EL_DBG_OK;
    case EL_DBG_CMD_BREAK:
        if (n != 0u) {
            return EL_DBG_E_LENGTH;
        }
        if (!halted) {
            halt_request = true;
            halt_why = EL_DBG_WHY_BREAK;
            update_armed();
        }
        return EL_DBG_OK;
    case EL_DBG_CMD_STEP:
        if (n != 1u) {
            return EL_DBG_E_LENGTH;
        }
        if (p[0] != EL_DBG_STEP_TASK && p[0] != EL_DBG_STEP_CHART && p[0] != EL_DBG_STEP_ACTOR
            && p[0] != EL_DBG_STEP_INSTANT) {
            return EL_DBG_E_VALUE;
        }
        if (!halted) {
            return EL_DBG_E_NOT_HALTED;
        }
        step_unit = p[0];
        halted = false;
        update_armed();
        return EL_DBG_OK;
    case EL_DBG_CMD_RESET:
        if (n > 1u) {
            return EL_DBG_E_LENGTH;
        }
        reset_pending = true;
        reset_flags = n == 1u ? p[0] : 0u;
        return EL_DBG_OK;
    case EL_DBG_CMD_BP_SET:
        return do_bp_set(p, n);
    case EL_DBG_CMD_BP_CLEAR:
        return do_bp_clear(p, n);
    case EL_DBG_CMD_BP_LIST:
        if (n != 0u) {
            return EL_DBG_E_LENGTH;
        }
        (void)put_u8(bp_count);
        for (i = 0u; i < EL_DBG_BP_SLOTS; i++) {
            if (bps[i].used != 0u) {
                (void)put_u8(i);
                (void)put_u8(bps[i].kind);
                (void)put_u16(bps[i].a);
                (void)put_u16(bps[i].b);
                (void)put_u16(bps[i].hits);
            }
        }
        return EL_DBG_OK;
    default:
#if defined(EL_DEBUG_BOARD_COMMANDS) && EL_DEBUG_BOARD_COMMANDS
        if (cmd >= EL_DBG_CMD_BOARD_FIRST && cmd <= EL_DBG_CMD_BOARD_LAST) {
            return el_debug_port_command(cmd, p, n);
        }
#endif
        return EL_DBG_E_UNKNOWN_CMD;
    }
}

#if defined(EL_DEBUG_BOARD_COMMANDS) && EL_DEBUG_BOARD_COMMANDS
bool el_debug_put(const uint8_t *data, uint16_t n)
{
    uint16_t i;
    for (i = 0u; i < n; i++) {
        if (!put_u8(data[i])) {
            return false;
        }
    }
    return true;
}
#endif

static void send_response(void)
{
    uint16_t crc = el_crc16(resp, resp_len);
    resp[resp_len++] = (uint8_t)(crc & 0xFFu);
    resp[resp_len++] = (uint8_t)(crc >> 8);
    wire_len = el_cobs_encode(resp, resp_len, wire, (uint16_t)sizeof wire);
    if (wire_len == 0u || !el_debug_port_write(wire, wire_len)) {
        count(EL_DBG_C_TX_DROPPED);
    }
}

/* A complete decoded frame is in rx_buf[0 .. len). */
static void handle_frame(uint16_t len)
{
    uint16_t crc;
    uint8_t seq, cmd, status;
    if (len < EL_DBG_HEADER + EL_DBG_TRAILER) {
        count(EL_DBG_C_TRUNCATED);
        return;
    }
    crc = get_u16(rx_buf + len - 2u);
    if (el_crc16(rx_buf, (uint16_t)(len - 2u)) != crc) {
        count(EL_DBG_C_BAD_CRC);
        return;
    }
    seq = rx_buf[0];
    cmd = rx_buf[1];
    if ((cmd & EL_DBG_RESPONSE) != 0u) {
        count(EL_DBG_C_UNKNOWN); /* a response (an echo?) is no request: drop it */
        return;
    }
    count(EL_DBG_C_FRAMES);
    if (cmd != EL_DBG_CMD_HELLO && have_last) {
        if (seq == last_seq && crc == last_crc && wire_len != 0u) {
            /* The host repeats a request whose response it lost: resend,
             * do not run it twice. */
            count(EL_DBG_C_DUPLICATES);
            if (!el_debug_port_write(wire, wire_len)) {
                count(EL_DBG_C_TX_DROPPED);
            }
            return;
        }
        if (seq != (uint8_t)(last_seq + 1u)) {
            count(EL_DBG_C_SEQ_GAPS);
        }
    }
    have_last = true;
    last_seq = seq;
    last_crc = crc;
    resp[0] = seq;
    resp[1] = (uint8_t)(cmd | EL_DBG_RESPONSE);
    resp[2] = EL_DBG_OK;
    resp_len = 3u;
    resp_full = false;
    status = dispatch(cmd, rx_buf + EL_DBG_HEADER, (uint16_t)(len - EL_DBG_HEADER - EL_DBG_TRAILER));
    if (status != EL_DBG_OK) {
        resp[2] = status;
        resp_len = 3u;
    resp_full = false;
        count(status == EL_DBG_E_UNKNOWN_CMD ? EL_DBG_C_UNKNOWN : EL_DBG_C_ERRORS);
    }
    send_response();
}

static void rx_byte(uint8_t byte)
{
    uint8_t r = el_cobs_decode_byte(&rx, byte);
    if (r == EL_COBS_FRAME) {
        handle_frame(rx.len);
    } else if (r == EL_COBS_OVERSIZE) {
        count(EL_DBG_C_OVERSIZE);
    } else if (r == EL_COBS_BAD) {
        count(EL_DBG_C_TRUNCATED);
    }
}

void el_debug_rx(const uint8_t *data, uint16_t len)
{
    uint16_t i;
    if (!rx_ready) {
        el_debug_boot();
    }
    for (i = 0u; i < len; i++) {
        rx_byte(data[i]);
    }
}

void el_debug_boot(void)
{
    el_cobs_decoder_init(&rx, rx_buf, (uint16_t)sizeof rx_buf);
    rx_ready = true;
    have_last = false; /* a new client: no repeated request to recognise */
    wire_len = 0u;
    update_armed();
}

void el_debug_poll(void)
{
    uint8_t chunk[16];
    uint16_t total = 0u, n;
    if (!rx_ready) {
        el_debug_boot();
    }
    while (total < EL_DBG_POLL_BYTES) {
        n = el_debug_port_read(chunk, (uint16_t)sizeof chunk);
        if (n == 0u) {
            break;
        }
        el_debug_rx(chunk, n > sizeof chunk ? (uint16_t)sizeof chunk : n);
        total = (uint16_t)(total + n);
    }
    if (reset_pending) {
        reset_pending = false;
        if (!el_debug_port_reset(reset_flags)) {
            count(EL_DBG_C_ERRORS);
        }
    }
}

#else
/* No debug interface in this model: nothing to compile (ISO C wants a
 * declaration in every translation unit). */
typedef int el_debug_unused_t;
#endif /* EL_DEBUG_SERVER */
