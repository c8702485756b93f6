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
 *
 * Small on 8-bit parts (docs/benchmarks.md, "Footprint goals"): values move
 * as bytes (one path for reads, writes and transactions; a queued entry
 * holds its element's address and size, not its ids), range checks compare
 * order-preserving 32-bit keys (no float arithmetic), every response is
 * built by one bounded `put8` and checked for size once, a request is
 * COBS-decoded in place in the buffer that received it and the response
 * encoded in place in the buffer that keeps it for a repeated request,
 * and payload lengths and indexes are 8-bit (frames are under 254 bytes).
 */
#include "el_debug.h"

#if defined(EL_DEBUG_SERVER) && EL_DEBUG_SERVER

/* GCC's loop-invariant motion keeps table addresses and sizes in registers
 * that 8-bit parts then save and restore around every call: smaller
 * without it (about 90 bytes on the ATmega328P); the server's loops are
 * short. Value-range propagation and the loops' induction-variable
 * canonicalisation duplicate paths of the request handlers: 44 bytes more
 * off without them. */
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC optimize("no-move-loop-invariants", "no-tree-vrp", "no-tree-loop-ivcanon")
#endif

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
/* What the model has (el_debug_config.h, generated from its debug tables):
 * code for what it lacks is left out, so a model pays only for the probe
 * kinds and value kinds it uses; the protocol is the same (a chart id is
 * E_ID in a model without charts either way). Without the config (the
 * fuzz target, a board that does not generate it) everything is in. */
#ifndef EL_DBG_HAS_CHARTS
#define EL_DBG_HAS_CHARTS 1 /* charts: their probe points and stack */
#endif
#ifndef EL_DBG_RANGES_UNSIGNED
#define EL_DBG_RANGES_UNSIGNED 1 /* a range on an unsigned integer, time or bool item */
#endif
#ifndef EL_DBG_RANGES_SIGNED
#define EL_DBG_RANGES_SIGNED 1 /* ... on a signed integer item */
#endif
#ifndef EL_DBG_RANGES_FLOAT
#define EL_DBG_RANGES_FLOAT 1 /* ... on a float32 item */
#endif
#define HAS_RANGES (EL_DBG_RANGES_UNSIGNED || EL_DBG_RANGES_SIGNED || EL_DBG_RANGES_FLOAT)
/* Conditional breakpoints compare order keys (order_key) of every type. */
#define HAS_CONDS (EL_DBG_COND_SLOTS > 0)
#define KEYS_SIGNED (EL_DBG_RANGES_SIGNED || HAS_CONDS)
#define KEYS_FLOAT (EL_DBG_RANGES_FLOAT || HAS_CONDS)

#ifndef EL_DBG_HAS_ARRAYS
#define EL_DBG_HAS_ARRAYS 1 /* an item of more than one element */
#endif
/* The elements of an item whose table entry is `it`. */
#if EL_DBG_HAS_ARRAYS
#define ELEMENTS(it) ((it).count)
#else
#define ELEMENTS(it) 1u
#endif

/* The in-place encoding below needs no COBS block of 254 bytes or more. */
#if EL_DBG_FRAME > 253u
#error "el_debug.c: a frame of more than 253 bytes needs a COBS encoder with long blocks"
#endif

/* ---- state ----------------------------------------------------------------- */

/* A queued read or write of one element: where it is in memory, its size
 * (ENTRY_WRITE set for a write; the item was checked when queued) and its
 * value in the wire's order (to write, or read when applied). */
typedef struct {
    uint8_t *addr;
    uint8_t size;
    uint8_t value[EL_DBG_VALUE_BYTES];
} entry_t;
#define ENTRY_WRITE 0x80u
#define ENTRY_SIZE 0x7Fu

typedef struct {
    uint8_t kind; /* EL_DBG_P_...; EL_DBG_P_NONE: a free slot */
    uint16_t a;
    uint16_t b;
    uint16_t hits;
} breakpoint_t;

#define TX_NONE 0u
#define TX_OPEN 1u      /* TX_RESULT reports these numbers as they are */
#define TX_COMMITTED 2u
#define TX_APPLIED 3u

/* The frame being received, as it comes (COBS): decoded in place at its
 * delimiter. A COBS frame of n < 254 bytes is n + 1 bytes; rx_len counts
 * one byte beyond rx_buf for a frame that outgrew it. Every variable of
 * the server starts at zero or its initialiser: the server needs no
 * start (el_debug_boot only forgets a client). */
static uint8_t rx_buf[EL_DBG_FRAME + 1u];
#define rx_frame (rx_buf + 1) /* the decoded frame (cobs_decode) */
static uint8_t rx_len;
/* The response: [0] COBS code, then seq, cmd, status, payload, CRC, then
 * the delimiter; encoded in place, kept for a repeated request. */
static uint8_t out[EL_DBG_FRAME + 2u];
#define resp (out + 1)
static uint8_t resp_len;  /* bytes of resp in use (seq, cmd, status, payload) */
static bool resp_full;    /* a put8 did not fit: the response is EL_DBG_E_TOO_BIG */
static uint8_t wire_len;  /* the last response as sent (0: none since the client came) */
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

#if EL_DBG_FORCE_SLOTS > 0
/* A forced element: a write (entry) applied again at every instant, and
 * the ids FORCE_LIST reports. In use: forces[0 .. force_count). */
typedef struct {
    entry_t e;
    uint16_t id;
    uint16_t elem;
} force_t;
static force_t forces[EL_DBG_FORCE_SLOTS];
static uint8_t force_count;
static bool forcing; /* the WRITE path serves a FORCE: hold, not submit */
#endif

#if HAS_CONDS
/* A conditional breakpoint: element `addr` of `type` compared (op) with
 * `value` (the wire's order, zero-padded to 4 bytes); it halts when the
 * comparison turns true. addr NULL: a free slot. Its slot number on the
 * wire is EL_DBG_BP_SLOTS + its index. */
typedef struct {
    uint8_t *addr;
    uint8_t type;
    uint8_t op;
    bool was_true;
    uint8_t value[EL_DBG_VALUE_MAX];
    uint16_t id;
    uint16_t elem;
    uint16_t hits;
} cond_t;
static cond_t conds[EL_DBG_COND_SLOTS];
static uint8_t cond_count;
#endif

uint8_t el_dbg_armed;
#if EL_DBG_HAS_FORCE_POINT
uint8_t el_dbg_forcing;
#endif
volatile uint8_t el_debug_abort_halt;
static bool halt_request;
static uint8_t halt_why; /* EL_DBG_WHY_... of the current or next halt */
static uint8_t step_unit;
static uint8_t loc_kind; /* EL_DBG_P_NONE: not halted */
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

#if EL_DBG_HAS_FORCE_POINT
/* el_dbg_forcing: is anything forced or a condition set? */
static void update_forcing(void)
{
    el_dbg_forcing = 0u;
#if EL_DBG_FORCE_SLOTS > 0
    el_dbg_forcing |= force_count;
#endif
#if HAS_CONDS
    el_dbg_forcing |= cond_count;
#endif
}
#endif

static void update_armed(void)
{
    el_dbg_armed = (uint8_t)((halt_request || step_unit != 0u || bp_count != 0u) && el_debug_abort_halt == 0u);
}

static uint16_t get_u16(const uint8_t *p)
{
    return (uint16_t)((uint16_t)p[0] | (uint16_t)((uint16_t)p[1] << 8));
}

/* Append a byte; a response that would outgrow the frame becomes
 * EL_DBG_E_TOO_BIG (handle_frame). Wider values low byte first. */
static void put8(uint8_t v)
{
    if (resp_len >= EL_DBG_FRAME - EL_DBG_TRAILER) {
        resp_full = true;
    } else {
        resp[resp_len++] = v;
    }
}

static void put16(uint16_t v)
{
    put8((uint8_t)(v & 0xFFu));
    put8((uint8_t)(v >> 8));
}

static void put32(uint32_t v)
{
    put16((uint16_t)(v & 0xFFFFu));
    put16((uint16_t)(v >> 16));
}

static void put_bytes(const uint8_t *p, uint8_t n)
{
    while (n-- != 0u) {
        put8(*p++);
    }
}

/* ---- values ------------------------------------------------------------------ */

static uint8_t type_size(uint8_t type)
{
    return type <= EL_DBG_T_U8 ? 1u : type <= EL_DBG_T_U16 ? 2u : 4u;
}

static void copy_bytes(uint8_t *dst, const uint8_t *src, uint8_t n)
{
    while (n-- != 0u) {
        *dst++ = *src++;
    }
}

/* The wire is little-endian; memory is the target's order: the board's
 * EL_LITTLE_ENDIAN or the compiler's, else tested at run time. Known
 * little-endian, a value moves as a plain copy. */
#if defined(EL_LITTLE_ENDIAN)
#define NATIVE_LE_KNOWN EL_LITTLE_ENDIAN
#elif defined(__BYTE_ORDER__) && defined(__ORDER_LITTLE_ENDIAN__)
#define NATIVE_LE_KNOWN (__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__)
#else
#define NATIVE_LE_KNOWN 0
#endif

/* Copy one value between memory and the wire (the same move both ways:
 * reversing the bytes is its own inverse). */
#if NATIVE_LE_KNOWN
#define move_value(dst, src, size) copy_bytes((dst), (src), (size))
#else
static const uint16_t one16 = 1u;
#define NATIVE_LE (*(const uint8_t *)&one16 == 1u)

static void move_value(uint8_t *dst, const uint8_t *src, uint8_t size)
{
    uint8_t i;
    for (i = 0u; i < size; i++) {
        dst[i] = src[NATIVE_LE ? i : (uint8_t)(size - 1u - i)];
    }
}
#endif

#if HAS_RANGES || HAS_CONDS
/* A value of `size` bytes from the wire, zero-extended: its bytes in a
 * 4-byte wire value, moved into memory's order (no shifts by 8, which
 * cost much code on 8-bit parts). */
static uint32_t le32(const uint8_t *in, uint8_t size)
{
    uint8_t wire[4] = {0u, 0u, 0u, 0u};
    uint32_t v;
    copy_bytes(wire, in, size);
    move_value((uint8_t *)&v, wire, 4u);
    return v;
}
#endif

/* Copy entry `index` of a debug table (EL_ROM) of `size`-byte entries
 * into RAM. The entry's offset is summed bit by bit of the size: no
 * multiplication routine on parts without a multiplier for it. */
static void rom_copy(void *dst, const void *table, uint16_t index, uint8_t size)
{
    const uint8_t *rom = (const uint8_t *)table;
    uint8_t i;
    for (i = size; i != 0u; i >>= 1) {
        if ((i & 1u) != 0u) {
            rom += index;
        }
        index <<= 1;
    }
    for (i = 0u; i < size; i++) {
        ((uint8_t *)dst)[i] = EL_ROM_READ_U8(rom + i);
    }
}

/* The item with this id into *it; false when there is none (an id from
 * outside). */
static bool load_item(uint16_t id, el_dbg_item_t *it)
{
    if (id >= el_dbg_item_count) {
        return false;
    }
    rom_copy(it, el_dbg_items, id, (uint8_t)sizeof *it);
    return true;
}

/* A 32-bit key of a value of `type` (its bits in u, a range bound's or a
 * written value's) that orders as the values do: signed integers
 * sign-extended with the sign bit flipped, floats by their IEEE bits with
 * the sign bit set, a negative one negated (-0 keys as +0; a NaN orders
 * beyond the infinities, so it is out of any finite range as a float
 * comparison has it). */
#if KEYS_FLOAT || KEYS_SIGNED
static uint32_t order_key(uint8_t type, uint32_t u)
{
#if KEYS_FLOAT
    if (type == EL_DBG_T_F32) {
        return (u & 0x80000000uL) != 0u ? (uint32_t)0u - u : (u | 0x80000000uL); /* -0: 0 - 0x80000000, +0's key */
    }
#endif
#if KEYS_SIGNED
    if (type == EL_DBG_T_I8) {
        u = (uint32_t)(int32_t)(int8_t)(uint8_t)u; /* sign-extended */
    } else if (type == EL_DBG_T_I16) {
        u = (uint32_t)(int32_t)(int16_t)(uint16_t)u;
    } else if (type != EL_DBG_T_I32) {
        return u; /* unsigned, time, bool */
    }
    return u ^ 0x80000000uL;
#else
    (void)type;
    return u; /* only unsigned ranges (and floats, above) in this model */
#endif
}
#else
#define order_key(type, u) (u) /* only unsigned ranges in this model, if any */
#endif

/* The item's range into *r; false when writes are not checked. */
static bool load_range(const el_dbg_item_t *it, el_dbg_range_t *r)
{
#if HAS_RANGES
    if ((it->flags & EL_DBG_F_RANGE) == 0u || it->range == EL_DBG_NONE16) {
        return false;
    }
    rom_copy(r, el_dbg_ranges, it->range, (uint8_t)sizeof *r);
    return true;
#else
    (void)it;
    (void)r;
    return false; /* no item of this model has a range */
#endif
}

/* Is `in` (type_size bytes, little-endian) an acceptable value of the item? */
static uint8_t check_value(const el_dbg_item_t *it, const uint8_t *in)
{
    if (it->type == EL_DBG_T_BOOL && in[0] > 1u) {
        return EL_DBG_E_VALUE;
    }
#if HAS_RANGES
    {
        el_dbg_range_t r;
        uint32_t key;
        if (!load_range(it, &r)) {
            return EL_DBG_OK;
        }
        key = order_key(it->type, le32(in, type_size(it->type)));
        return (key >= order_key(it->type, r.lo.u) && key <= order_key(it->type, r.hi.u)) ? EL_DBG_OK
                                                                                            : EL_DBG_E_RANGE;
    }
#else
    return EL_DBG_OK;
#endif
}

/* Move an entry's element between memory and the entry. */
static void apply(entry_t *e)
{
    uint8_t *dst = e->value;
    const uint8_t *src = e->addr;
    if ((e->size & ENTRY_WRITE) != 0u) {
        dst = e->addr;
        src = e->value;
    }
    move_value(dst, src, (uint8_t)(e->size & ENTRY_SIZE));
}

static bool at_instant(void)
{
#if HAS_CONDS
    if (loc_kind == EL_DBG_P_CONDITION) {
        return true; /* an instant too: after its device reads, before its releases */
    }
#endif
    return loc_kind == EL_DBG_P_INSTANT;
}

/* The queued writes, then a committed transaction: at an instant's inputs. */
static void apply_all(entry_t *q, uint8_t n)
{
    while (n-- != 0u) {
        apply(q); /* q as it is, not q++: on the PIC18 it then stays a two-byte RAM pointer (datapointers.py) */
        q++;
    }
}

static void apply_queues(void)
{
    apply_all(wq, wq_len);
    wq_len = 0u;
    if (tx_state == TX_COMMITTED) {
        apply_all(txq, tx_len);
        tx_state = TX_APPLIED;
    }
}

/* ---- halting ---------------------------------------------------------------- */

static void clear_bps(void)
{
    breakpoint_t *bp = bps;
    uint8_t i;
    for (i = 0u; i < EL_DBG_BP_SLOTS; i++, bp++) {
        bp->kind = EL_DBG_P_NONE;
    }
    bp_count = 0u;
#if HAS_CONDS
    for (i = 0u; i < EL_DBG_COND_SLOTS; i++) {
        conds[i].addr = NULL;
    }
    cond_count = 0u;
    update_forcing();
#endif
}

/* Cancel a pending break or step, then step to the next probe of `unit`
 * (0: none). */
static void set_step(uint8_t unit)
{
    halt_request = false;
    step_unit = unit;
    update_armed();
}

/* The program goes on: no halt location (halt_here returns). */
static void resume(void)
{
    halt_why = EL_DBG_WHY_NONE;
    loc_kind = EL_DBG_P_NONE;
    loc_a = loc_b = EL_DBG_NONE16;
    loc_bp = EL_DBG_NONE8;
}

static void halt_here(uint8_t why, uint8_t kind, uint16_t a, uint16_t b, uint8_t bp)
{
    halt_why = why;
    loc_kind = kind;
    loc_a = a;
    loc_b = b;
    loc_bp = bp;
    set_step(0u);
    while (loc_kind != EL_DBG_P_NONE && el_debug_abort_halt == 0u) {
        el_port_idle(EL_DBG_IDLE_MS);
    }
    resume();
    if (el_debug_abort_halt != 0u) {
        clear_bps();
        set_step(0u);
    }
    el_port_resync();
}

/* The slot of the breakpoint at (kind, a, b), or EL_DBG_NONE8; for
 * EL_DBG_P_NONE, the first free slot. The slots are walked by pointer:
 * an index would multiply by the slot's size at every access. */
static uint8_t find_bp(uint8_t kind, uint16_t a, uint16_t b)
{
    const breakpoint_t *bp = bps;
    uint8_t i;
    for (i = 0u; i < EL_DBG_BP_SLOTS; i++, bp++) {
        if (bp->kind == kind && (kind == EL_DBG_P_NONE || (bp->a == a && bp->b == b))) {
            return i;
        }
    }
    return EL_DBG_NONE8;
}

void el_debug_probe(uint8_t kind, uint16_t a, uint16_t b)
{
    uint8_t i, why = EL_DBG_WHY_NONE;
    if (el_debug_abort_halt != 0u || loc_kind != EL_DBG_P_NONE) {
        return;
    }
    i = find_bp(kind, a, b);
    if (i != EL_DBG_NONE8) {
        breakpoint_t *bp = &bps[i];
        if (bp->hits != UINT16_MAX) {
            bp->hits++;
        }
        why = EL_DBG_WHY_BREAKPOINT;
    } else if (step_unit == kind) {
        why = EL_DBG_WHY_STEP;
    } else if (halt_request && kind == EL_DBG_P_INSTANT) {
        why = halt_why == EL_DBG_WHY_START ? EL_DBG_WHY_START : EL_DBG_WHY_BREAK;
    }
    if (why != EL_DBG_WHY_NONE) {
        halt_here(why, kind, a, b, i);
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
    uint16_t a_limit, b_limit = 1u;
    switch (kind) {
    case EL_DBG_P_INSTANT:
        a_limit = 1u;
        break;
    case EL_DBG_P_TASK:
        a_limit = el_task_count;
        break;
    case EL_DBG_P_ACTOR:
        a_limit = el_dbg_actor_count;
        break;
#if EL_DBG_HAS_CHARTS
    case EL_DBG_P_CHART:
    case EL_DBG_P_STEP:
    case EL_DBG_P_TRANSITION:
        a_limit = el_dbg_chart_count;
        if (a < a_limit && kind != EL_DBG_P_CHART) {
            el_dbg_chart_t c;
            rom_copy(&c, el_dbg_charts, a, (uint8_t)sizeof c);
            b_limit = kind == EL_DBG_P_STEP ? c.step_count : c.transition_count;
        }
        break;
#endif
    default:
        return false;
    }
    return a < a_limit && b < b_limit;
}

static void put_location(void)
{
    put8(loc_kind != EL_DBG_P_NONE ? 1u : 0u);
    put8(halt_why);
    put8(loc_kind);
    put16(loc_a);
    put16(loc_b);
    put8(loc_bp);
}

/* The values of the applied transaction's reads. */
static void put_tx_reads(void)
{
    uint8_t i;
    for (i = 0u; i < tx_len; i++) {
        if ((txq[i].size & ENTRY_WRITE) == 0u) {
            put_bytes(txq[i].value, txq[i].size);
        }
    }
}

/* One element's read or write, the one path of READ, WRITE and
 * transactions: queued in the open transaction; a write queued for the
 * next instant, or applied at once at a halted instant; a read into the
 * response. */
/* Append *e to the queue q of *len entries (max at most): false when it
 * is full. */
static bool enqueue(entry_t *q, uint8_t *len, uint8_t max, const entry_t *e)
{
    if (*len >= max) {
        return false;
    }
    copy_bytes((uint8_t *)(q + (*len)++), (const uint8_t *)e, (uint8_t)sizeof *e);
    return true;
}

static uint8_t submit(entry_t *e)
{
    bool write = (e->size & ENTRY_WRITE) != 0u;
    if (tx_state == TX_OPEN) {
        return enqueue(txq, &tx_len, EL_DBG_TX_ENTRIES, e) ? EL_DBG_OK : EL_DBG_E_QUEUE_FULL;
    }
    if (write && !at_instant()) {
        if (!enqueue(wq, &wq_len, EL_DBG_WRITE_ENTRIES, e)) {
            return EL_DBG_E_QUEUE_FULL;
        }
        put8(EL_DBG_QUEUED);
    } else {
        apply(e);
        if (write) {
            put8(EL_DBG_APPLIED);
        } else {
            put_bytes(e->value, e->size);
        }
    }
    return EL_DBG_OK;
}

#if EL_DBG_FORCE_SLOTS > 0
/* The index of the force of (id, elem), or force_count: none. */
static uint8_t find_force(uint16_t id, uint16_t elem)
{
    uint8_t i;
    for (i = 0u; i < force_count && (forces[i].id != id || forces[i].elem != elem); i++) {
    }
    return i;
}

/* FORCE's end of the WRITE path (do_access, `forcing`): the checked write
 * *e of (id, elem) held from the next instant on (at once when halted at
 * an instant), until RELEASE; forcing an element again changes its value. */
static uint8_t hold(const entry_t *e, uint16_t id, uint16_t elem)
{
    uint8_t i = find_force(id, elem);
    if (i == force_count) {
        if (force_count >= EL_DBG_FORCE_SLOTS) {
            return EL_DBG_E_FORCE_FULL;
        }
        force_count++;
        update_forcing();
    }
    copy_bytes((uint8_t *)&forces[i].e, (const uint8_t *)e, (uint8_t)sizeof *e);
    forces[i].id = id;
    forces[i].elem = elem;
    if (at_instant()) {
        apply(&forces[i].e);
        put8(EL_DBG_APPLIED);
    } else {
        put8(EL_DBG_QUEUED);
    }
    return EL_DBG_OK;
}
#endif

/* READ (p[n]: item ids, every element of each) and WRITE (p[n]: id, element,
 * value); FORCE is a WRITE held (`forcing`). In an open transaction the
 * response is QUEUED and the index of the first entry; a request queues
 * all of its elements or none (an error takes back what it queued; a
 * response with an error carries nothing). */
static uint8_t do_access(bool write, const uint8_t *p, uint8_t n)
{
    uint8_t k, first = tx_len, st = EL_DBG_OK;
    uint16_t elem;
    el_dbg_item_t it;
    entry_t e;
    if (write ? n < 5u : (n == 0u || (n & 1u) != 0u)) {
        return EL_DBG_E_LENGTH;
    }
    if (tx_state == TX_OPEN) {
        put8(EL_DBG_QUEUED);
        put8(first);
    }
    for (k = 0u; k < n && st == EL_DBG_OK; k += 2u) {
        if (!load_item(get_u16(p + k), &it)) {
            st = EL_DBG_E_ID;
            break;
        }
        e.size = type_size(it.type);
        e.addr = (uint8_t *)it.addr;
        if (write) {
            elem = get_u16(p + 2);
            if (n != 4u + e.size) {
                st = EL_DBG_E_LENGTH;
            } else if ((it.flags & EL_DBG_F_WRITE) == 0u) {
                st = EL_DBG_E_READ_ONLY;
            } else if (elem >= ELEMENTS(it)) {
                st = EL_DBG_E_VALUE;
            } else {
                st = check_value(&it, p + 4);
            }
            if (st == EL_DBG_OK) {
                e.addr += elem << (e.size >> 1); /* sizes 1, 2, 4: no multiplication */
                for (k = 0u; k < e.size; k++) {
                    e.value[k] = p[4u + k]; /* the wire's order: apply moves it to memory */
                }
                e.size |= ENTRY_WRITE;
#if EL_DBG_FORCE_SLOTS > 0
                st = forcing ? hold(&e, get_u16(p), elem) : submit(&e);
#else
                st = submit(&e);
#endif
            }
            break; /* one element of one item */
        }
        for (elem = 0u; elem < ELEMENTS(it) && st == EL_DBG_OK && !resp_full; elem++) {
            st = submit(&e);
            e.addr += e.size;
        }
    }
    if (st != EL_DBG_OK) {
        tx_len = first;
    }
    return st;
}

#if EL_DBG_FORCE_SLOTS > 0
/* RELEASE (id, element; id NONE16: every force): the element keeps its
 * value until the program or the stimulus changes it. */
static uint8_t do_release(const uint8_t *p)
{
    uint16_t id = get_u16(p);
    uint8_t i;
    if (id == EL_DBG_NONE16) {
        force_count = 0u;
        update_forcing();
        return EL_DBG_OK;
    }
    i = find_force(id, get_u16(p + 2));
    if (i == force_count) {
        return EL_DBG_E_ID;
    }
    force_count--;
    copy_bytes((uint8_t *)&forces[i], (const uint8_t *)&forces[force_count], (uint8_t)sizeof forces[0]);
    update_forcing();
    return EL_DBG_OK;
}

static void put_forces(void)
{
    uint8_t i, size;
    put8(force_count);
    for (i = 0u; i < force_count; i++) {
        size = (uint8_t)(forces[i].e.size & ENTRY_SIZE);
        put16(forces[i].id);
        put16(forces[i].elem);
        put8(size);
        put_bytes(forces[i].e.value, size);
    }
}
#endif

#if HAS_CONDS
/* Is the condition true now? Both sides compare as order keys (order_key:
 * signed, unsigned and float values as their type orders them); each
 * operator is the set of outcomes (greater, equal, less: bits 0, 1, 2) for
 * which it holds, so one 32-bit comparison pair serves all six. */
static const uint8_t op_outcomes[] EL_ROM = {
    0x02u, /* EL_DBG_OP_EQ */
    0x05u, /* EL_DBG_OP_NE */
    0x04u, /* EL_DBG_OP_LT */
    0x06u, /* EL_DBG_OP_LE */
    0x01u, /* EL_DBG_OP_GT */
    0x03u, /* EL_DBG_OP_GE */
};
typedef char op_outcomes_cover_the_ops[sizeof op_outcomes == EL_DBG_OP_GE + 1u ? 1 : -1];

static bool cond_holds(const cond_t *c)
{
    uint8_t size = type_size(c->type), now[EL_DBG_VALUE_MAX], outcome = 0u;
    uint32_t x, k;
    move_value(now, c->addr, size); /* memory's order to the wire's */
    x = order_key(c->type, le32(now, size));
    k = order_key(c->type, le32(c->value, size));
    if (x == k) {
        outcome = 1u;
    } else if (x < k) {
        outcome = 2u;
    }
    return ((EL_ROM_READ_U8(&op_outcomes[c->op]) >> outcome) & 1u) != 0u;
}

/* BP_WHEN (p[n]: id u16, element u16, op u8, value): a conditional
 * breakpoint on any readable element, in a slot of its own. It is false
 * until evaluated: one that holds when set halts at the next instant. */
static uint8_t do_bp_when(const uint8_t *p, uint8_t n)
{
    el_dbg_item_t it;
    cond_t *c;
    uint8_t i, size, free_slot = EL_DBG_NONE8;
    uint16_t id = get_u16(p), elem;
    if (n < 6u) {
        return EL_DBG_E_LENGTH;
    }
    if (!load_item(id, &it)) {
        return EL_DBG_E_ID;
    }
    size = type_size(it.type);
    elem = get_u16(p + 2);
    if (n != 5u + size) {
        return EL_DBG_E_LENGTH;
    }
    if (elem >= ELEMENTS(it) || p[4] > EL_DBG_OP_GE || (it.type == EL_DBG_T_BOOL && p[5] > 1u)) {
        return EL_DBG_E_VALUE;
    }
    for (i = 0u, c = conds; i < EL_DBG_COND_SLOTS && free_slot == EL_DBG_NONE8; i++, c++) {
        if (c->addr == NULL) {
            free_slot = i;
        }
    }
    if (free_slot == EL_DBG_NONE8) {
        return EL_DBG_E_BP_FULL;
    }
    c = &conds[free_slot];
    c->addr = (uint8_t *)it.addr + (elem << (size >> 1));
    c->type = it.type;
    c->op = p[4];
    c->was_true = false;
    for (i = 0u; i < EL_DBG_VALUE_MAX; i++) {
        c->value[i] = i < size ? p[5u + i] : 0u;
    }
    c->id = id;
    c->elem = elem;
    c->hits = 0u;
    cond_count++;
    update_forcing();
    put8((uint8_t)(EL_DBG_BP_SLOTS + free_slot));
    return EL_DBG_OK;
}
#endif

#if EL_DBG_HAS_FORCE_POINT
void el_debug_force(void)
{
    uint8_t i;
#if EL_DBG_FORCE_SLOTS > 0
    for (i = 0u; i < force_count; i++) {
        apply(&forces[i].e);
    }
#endif
#if HAS_CONDS
    {
        uint8_t hit = EL_DBG_NONE8;
        cond_t *c = conds;
        bool now;
        for (i = 0u; i < EL_DBG_COND_SLOTS; i++, c++) {
            if (c->addr == NULL) {
                continue;
            }
            now = cond_holds(c);
            if (now && !c->was_true) { /* the edge: false -> true */
                if (c->hits != UINT16_MAX) {
                    c->hits++;
                }
                if (hit == EL_DBG_NONE8) {
                    hit = i;
                }
            }
            c->was_true = now;
        }
        if (hit != EL_DBG_NONE8 && el_debug_abort_halt == 0u && loc_kind == EL_DBG_P_NONE) {
            halt_here(EL_DBG_WHY_BREAKPOINT, EL_DBG_P_CONDITION, conds[hit].id, conds[hit].elem,
                      (uint8_t)(EL_DBG_BP_SLOTS + hit));
        }
    }
#endif
}
#endif

static uint8_t do_bp_set(const uint8_t *p)
{
    uint8_t kind = p[0], i;
    uint16_t a = get_u16(p + 1), b = get_u16(p + 3);
    if (!valid_point(kind, a, b)) {
        return EL_DBG_E_ID;
    }
    i = find_bp(kind, a, b); /* already set: the same slot */
    if (i == EL_DBG_NONE8) {
        i = find_bp(EL_DBG_P_NONE, 0u, 0u);
        if (i == EL_DBG_NONE8) {
            return EL_DBG_E_BP_FULL;
        }
        {
            breakpoint_t *bp = &bps[i];
            bp->kind = kind;
            bp->a = a;
            bp->b = b;
            bp->hits = 0u;
        }
        bp_count++;
        update_armed();
    }
    put8(i);
    return EL_DBG_OK;
}

static uint8_t do_bp_clear(uint8_t slot)
{
    if (slot == EL_DBG_NONE8) {
        clear_bps();
#if HAS_CONDS
    } else if (slot >= EL_DBG_BP_SLOTS && slot < EL_DBG_BP_SLOTS + EL_DBG_COND_SLOTS &&
               conds[slot - EL_DBG_BP_SLOTS].addr != NULL) {
        conds[slot - EL_DBG_BP_SLOTS].addr = NULL;
        cond_count--;
        update_forcing();
#endif
    } else if (slot >= EL_DBG_BP_SLOTS || bps[slot].kind == EL_DBG_P_NONE) {
        return EL_DBG_E_ID;
    } else {
        bps[slot].kind = EL_DBG_P_NONE;
        bp_count--;
    }
    update_armed();
    return EL_DBG_OK;
}

static void put_bps(void)
{
    const breakpoint_t *bp = bps;
    uint8_t i;
#if HAS_CONDS
    put8((uint8_t)(bp_count + cond_count));
#else
    put8(bp_count);
#endif
    for (i = 0u; i < EL_DBG_BP_SLOTS; i++, bp++) {
        if (bp->kind != EL_DBG_P_NONE) {
            put8(i);
            put8(bp->kind);
            put16(bp->a);
            put16(bp->b);
            put16(bp->hits);
        }
    }
#if HAS_CONDS
    for (i = 0u; i < EL_DBG_COND_SLOTS; i++) {
        const cond_t *c = &conds[i];
        if (c->addr != NULL) { /* then its op and value (4 bytes) */
            put8((uint8_t)(EL_DBG_BP_SLOTS + i));
            put8(EL_DBG_P_CONDITION);
            put16(c->id);
            put16(c->elem);
            put16(c->hits);
            put8(c->op);
            put_bytes(c->value, EL_DBG_VALUE_MAX);
        }
    }
#endif
}

static void put_stack(void)
{
    put32((uint32_t)el_now_tick());
    put_location();
    put8(running_task);
    put16(loc_kind == EL_DBG_P_ACTOR ? loc_a : EL_DBG_NONE16);
    put8(el_dbg_chart_count);
#if EL_DBG_HAS_CHARTS
    {
        uint8_t c;
        for (c = 0u; c < el_dbg_chart_count; c++) {
            el_dbg_chart_t chart;
            rom_copy(&chart, el_dbg_charts, c, (uint8_t)sizeof chart);
            put8(chart.slot_count);
            put_bytes(chart.slots, chart.slot_count);
        }
    }
#endif
}

static void put_hello(void)
{
    put8(EL_DBG_PROTOCOL_VERSION);
    put16(EL_DBG_FRAME);
    put8(EL_DBG_WINDOW);
    put32(el_program_id);
    put16(el_dbg_item_count);
    put16(el_dbg_actor_count);
    put8(el_dbg_chart_count);
    put8(el_task_count);
    put8(EL_DBG_TX_ENTRIES);
    put8(EL_DBG_WRITE_ENTRIES);
    put8(EL_DBG_BP_SLOTS);
    put8(EL_DBG_VALUE_MAX);
#if EL_DBG_HAS_FORCE_POINT /* absent: no slots (2 bytes fewer in a server short of flash) */
    put8(EL_DBG_FORCE_SLOTS);
    put8(EL_DBG_COND_SLOTS);
#endif
}

static void put_flags(void)
{
    uint8_t f = loc_kind != EL_DBG_P_NONE ? EL_DBG_S_HALTED : 0u;
    if (tx_state != TX_NONE) {
        f |= (uint8_t)(EL_DBG_S_TX_OPEN << (tx_state - TX_OPEN)); /* OPEN, COMMITTED, APPLIED in a row */
    }
    if (wq_len != 0u) {
        f |= EL_DBG_S_WRITES_PENDING;
    }
    if (halt_request || step_unit != 0u) {
        f |= EL_DBG_S_HALT_PENDING;
    }
#if EL_DBG_FORCE_SLOTS > 0
    if (force_count != 0u) {
        f |= EL_DBG_S_FORCED;
    }
#endif
    put8(f);
    put_location();
    put32((uint32_t)el_now_tick());
    put8(wq_len);
    put8(tx_len);
}
#if EL_DBG_S_TX_COMMITTED != EL_DBG_S_TX_OPEN << 1 || EL_DBG_S_TX_APPLIED != EL_DBG_S_TX_OPEN << 2
#error "put_flags: the transaction's status flags must follow each other"
#endif

static uint8_t put_item_info(uint16_t id)
{
    el_dbg_item_t it;
    el_dbg_range_t r;
    if (!load_item(id, &it)) {
        return EL_DBG_E_ID;
    }
    if (!load_range(&it, &r)) {
        r.lo.u = r.hi.u = 0u;
    }
    put8(it.type);
    put8(it.kind);
    put8(it.flags);
    put16(it.count);
    put32(r.lo.u);
    put32(r.hi.u);
    return EL_DBG_OK;
}

/* The requests: command byte and the payload length it must have
 * (ANY_LENGTH: its handler checks), in the order of enum request. */
#define ANY_LENGTH 0xFFu
static const uint8_t requests[][2] EL_ROM = {
    {EL_DBG_CMD_HELLO, 0u},
    {EL_DBG_CMD_GET_PROGRAM_ID, 0u},
    {EL_DBG_CMD_GET_FLAGS, 0u},
    {EL_DBG_CMD_GET_COUNTERS, 0u},
    {EL_DBG_CMD_ITEM_INFO, 2u},
    {EL_DBG_CMD_READ, ANY_LENGTH},
    {EL_DBG_CMD_WRITE, ANY_LENGTH},
    {EL_DBG_CMD_TX_BEGIN, 0u},
    {EL_DBG_CMD_TX_COMMIT, 0u},
    {EL_DBG_CMD_TX_ABORT, 0u},
    {EL_DBG_CMD_TX_RESULT, 0u},
    {EL_DBG_CMD_GET_STACK, 0u},
    {EL_DBG_CMD_RUN, 0u},
    {EL_DBG_CMD_BREAK, 0u},
    {EL_DBG_CMD_STEP, 1u},
    {EL_DBG_CMD_RESET, ANY_LENGTH},
    {EL_DBG_CMD_BP_SET, 5u},
    {EL_DBG_CMD_BP_CLEAR, 1u},
    {EL_DBG_CMD_BP_LIST, 0u},
#if EL_DBG_FORCE_SLOTS > 0 /* without slots these are unknown requests: HELLO says 0 */
    {EL_DBG_CMD_FORCE, ANY_LENGTH},
    {EL_DBG_CMD_RELEASE, 4u},
    {EL_DBG_CMD_FORCE_LIST, 0u},
#endif
#if HAS_CONDS
    {EL_DBG_CMD_BP_WHEN, ANY_LENGTH},
#endif
};
enum request {
    REQ_HELLO,
    REQ_GET_PROGRAM_ID,
    REQ_GET_FLAGS,
    REQ_GET_COUNTERS,
    REQ_ITEM_INFO,
    REQ_READ,
    REQ_WRITE,
    REQ_TX_BEGIN,
    REQ_TX_COMMIT,
    REQ_TX_ABORT,
    REQ_TX_RESULT,
    REQ_GET_STACK,
    REQ_RUN,
    REQ_BREAK,
    REQ_STEP,
    REQ_RESET,
    REQ_BP_SET,
    REQ_BP_CLEAR,
    REQ_BP_LIST,
#if EL_DBG_FORCE_SLOTS > 0
    REQ_FORCE,
    REQ_RELEASE,
    REQ_FORCE_LIST,
#endif
#if HAS_CONDS
    REQ_BP_WHEN,
#endif
    REQ_COUNT
};
typedef char requests_match_their_enum[sizeof requests / sizeof requests[0] == REQ_COUNT ? 1 : -1];

/* Run one request (cmd, payload p[n]); the response's status byte is at
 * resp[2], its payload follows. Returns the status. */
static uint8_t dispatch(uint8_t cmd, const uint8_t *p, uint8_t n)
{
    uint8_t i, req, want;
    for (req = 0u; req < REQ_COUNT && EL_ROM_READ_U8(&requests[req][0]) != cmd; req++) {
    }
    if (req < REQ_COUNT) {
        want = EL_ROM_READ_U8(&requests[req][1]);
        if (want != ANY_LENGTH && n != want) {
            return EL_DBG_E_LENGTH;
        }
    }
    switch (req) {
    case REQ_HELLO:
        put_hello();
        break;
    case REQ_GET_PROGRAM_ID:
        put32(el_program_id);
        break;
    case REQ_GET_FLAGS:
        put_flags();
        break;
    case REQ_GET_COUNTERS:
        put8(EL_DBG_C_COUNT);
        for (i = 0u; i < EL_DBG_C_COUNT; i++) {
            put16(counters[i]);
        }
        break;
    case REQ_ITEM_INFO:
        return put_item_info(get_u16(p));
    case REQ_READ:
    case REQ_WRITE:
        return do_access(req == REQ_WRITE, p, n);
    case REQ_TX_BEGIN:
        if (tx_state == TX_OPEN || tx_state == TX_COMMITTED) {
            return EL_DBG_E_TX_BUSY;
        }
        tx_state = TX_OPEN;
        tx_len = 0u;
        break;
    case REQ_TX_COMMIT:
        if (tx_state != TX_OPEN) {
            return EL_DBG_E_NO_TX;
        }
        tx_state = TX_COMMITTED;
        if (!at_instant()) {
            put8(EL_DBG_QUEUED);
            break;
        }
        apply_queues();
        put8(EL_DBG_APPLIED);
        put_tx_reads();
        break;
    case REQ_TX_ABORT:
        if (tx_state != TX_OPEN && tx_state != TX_COMMITTED) {
            return EL_DBG_E_NO_TX;
        }
        tx_state = TX_NONE;
        tx_len = 0u;
        break;
    case REQ_TX_RESULT:
        put8(tx_state);
        if (tx_state == TX_APPLIED) {
            put_tx_reads();
        }
        break;
    case REQ_GET_STACK:
        put_stack();
        break;
    case REQ_RUN:
        set_step(0u);
        resume();
        break;
    case REQ_BREAK:
        if (loc_kind == EL_DBG_P_NONE) {
            halt_request = true;
            halt_why = EL_DBG_WHY_BREAK;
            update_armed();
        }
        break;
    case REQ_STEP:
        /* A model without charts has no evolution to end: STEP_CHART is E_VALUE there. */
        if (p[0] != EL_DBG_STEP_TASK && p[0] != EL_DBG_STEP_ACTOR && p[0] != EL_DBG_STEP_INSTANT
#if EL_DBG_HAS_CHARTS
            && p[0] != EL_DBG_STEP_CHART
#endif
            ) {
            return EL_DBG_E_VALUE;
        }
        if (loc_kind == EL_DBG_P_NONE) {
            return EL_DBG_E_NOT_HALTED;
        }
        set_step(p[0]);
        resume();
        break;
    case REQ_RESET:
        if (n > 1u) {
            return EL_DBG_E_LENGTH;
        }
        reset_pending = true;
        reset_flags = n == 1u ? p[0] : 0u;
        break;
    case REQ_BP_SET:
        return do_bp_set(p);
    case REQ_BP_CLEAR:
        return do_bp_clear(p[0]);
    case REQ_BP_LIST:
        put_bps();
        break;
#if EL_DBG_FORCE_SLOTS > 0
    case REQ_FORCE:
        if (tx_state == TX_OPEN) {
            return EL_DBG_E_TX_BUSY; /* a force is not part of a transaction */
        }
        forcing = true;
        i = do_access(true, p, n);
        forcing = false;
        return i;
    case REQ_RELEASE:
        return do_release(p);
    case REQ_FORCE_LIST:
        put_forces();
        break;
#endif
#if HAS_CONDS
    case REQ_BP_WHEN:
        return do_bp_when(p, n);
#endif
    default:
#if defined(EL_DEBUG_BOARD_COMMANDS) && EL_DEBUG_BOARD_COMMANDS
        if (cmd >= EL_DBG_CMD_BOARD_FIRST && cmd <= EL_DBG_CMD_BOARD_LAST) {
            return el_debug_port_command(cmd, p, n);
        }
#endif
        return EL_DBG_E_UNKNOWN_CMD;
    }
    return EL_DBG_OK;
}

#if defined(EL_DEBUG_BOARD_COMMANDS) && EL_DEBUG_BOARD_COMMANDS
bool el_debug_put(const uint8_t *data, uint16_t n)
{
    uint16_t i;
    for (i = 0u; i < n && !resp_full; i++) {
        put8(data[i]);
    }
    return !resp_full;
}
#endif

/* Send the response in out[]: its CRC, then COBS in place. With frames of
 * fewer than 254 bytes every block is short: each zero byte (and the code
 * byte before the frame) becomes the distance to the next zero or the
 * delimiter. */
/* Send the last response (out[0 .. wire_len)). */
static void transmit(void)
{
    if (!el_debug_port_write(out, wire_len)) {
        count(EL_DBG_C_TX_DROPPED);
    }
}

static void send_response(void)
{
    uint16_t crc = el_crc16(resp, resp_len);
    uint8_t j, next;
    resp[resp_len++] = (uint8_t)(crc & 0xFFu);
    resp[resp_len++] = (uint8_t)(crc >> 8);
    next = (uint8_t)(resp_len + 1u);
    out[next] = EL_DBG_DELIMITER;
    for (j = resp_len; j > 0u; j--) {
        if (out[j] == 0u) {
            out[j] = (uint8_t)(next - j);
            next = j;
        }
    }
    out[0] = next;
    wire_len = (uint8_t)(resp_len + 2u);
    transmit();
}

/* A complete decoded frame is in rx_frame[0 .. len). */
static void handle_frame(uint8_t len)
{
    uint16_t crc;
    uint8_t seq, cmd, status;
    if (len < EL_DBG_HEADER + EL_DBG_TRAILER) {
        count(EL_DBG_C_TRUNCATED);
        return;
    }
    len = (uint8_t)(len - EL_DBG_TRAILER);
    crc = get_u16(rx_frame + len);
    if (el_crc16(rx_frame, len) != crc) {
        count(EL_DBG_C_BAD_CRC);
        return;
    }
    seq = rx_frame[0];
    cmd = rx_frame[1];
    if ((cmd & EL_DBG_RESPONSE) != 0u) {
        count(EL_DBG_C_UNKNOWN); /* a response (an echo?) is no request: drop it */
        return;
    }
    count(EL_DBG_C_FRAMES);
    if (cmd != EL_DBG_CMD_HELLO && wire_len != 0u) {
        if (seq == last_seq && crc == last_crc) {
            /* The host repeats a request whose response it lost: resend,
             * do not run it twice. */
            count(EL_DBG_C_DUPLICATES);
            transmit();
            return;
        }
        if (seq != (uint8_t)(last_seq + 1u)) {
            count(EL_DBG_C_SEQ_GAPS);
        }
    }
    last_seq = seq;
    last_crc = crc;
    resp[0] = seq;
    resp[1] = (uint8_t)(cmd | EL_DBG_RESPONSE);
    resp_len = 3u;
    resp_full = false;
    status = dispatch(cmd, rx_frame + EL_DBG_HEADER, (uint8_t)(len - EL_DBG_HEADER));
    if (status == EL_DBG_OK && resp_full) {
        status = EL_DBG_E_TOO_BIG;
    }
    resp[2] = status;
    if (status != EL_DBG_OK) {
        resp_len = 3u;
        count(status == EL_DBG_E_UNKNOWN_CMD ? EL_DBG_C_UNKNOWN : EL_DBG_C_ERRORS);
    }
    send_response();
}

/* Decode the COBS frame in rx_buf[0 .. rx_len) in place: false when a
 * block is cut. Each code byte gives the distance to the next one, and
 * each one after the first stands for a zero: the decoded frame is
 * rx_buf[1 .. rx_len) (rx_frame) once they are zeroed. A frame that fits
 * rx_buf has no full 254-byte block (code 0xFF): such a block is cut. */
static bool cobs_decode(void)
{
    uint8_t at = 0u, code;
    while (at < rx_len) {
        code = rx_buf[at];
        if (code > (uint8_t)(rx_len - at)) {
            return false;
        }
        rx_buf[at] = 0u;
        at = (uint8_t)(at + code);
    }
    return true;
}

/* One received byte: a frame ends at its delimiter. */
static void rx_byte(uint8_t b)
{
    if (b != EL_DBG_DELIMITER) {
        if (rx_len < sizeof rx_buf) {
            rx_buf[rx_len] = b;
        }
        if (rx_len <= sizeof rx_buf) {
            rx_len++;
        }
    } else {
        if (rx_len > sizeof rx_buf) {
            count(EL_DBG_C_OVERSIZE);
        } else if (rx_len != 0u) { /* a delimiter alone ends no frame */
            if (cobs_decode()) {
                handle_frame((uint8_t)(rx_len - 1u));
            } else {
                count(EL_DBG_C_TRUNCATED);
            }
        }
        rx_len = 0u;
    }
}

void el_debug_rx(const uint8_t *data, uint16_t len)
{
    while (len-- != 0u) {
        rx_byte(*data++);
    }
}

void el_debug_boot(void)
{
    rx_len = 0u;
    wire_len = 0u; /* a new client: no repeated request to recognise */
    update_armed();
}

void el_debug_poll(void)
{
    uint8_t b, k;
    for (k = 0u; k < EL_DBG_POLL_BYTES && el_debug_port_read(&b, 1u) != 0u; k++) {
        rx_byte(b);
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
