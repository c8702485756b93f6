/* EasyLab f16 board, 16-bit proxy: the simulation build's devices,
 * stimulus and trace (f16p.h has the streams' formats).
 *
 * As on the host board: a param's or var's stimulus value is written once,
 * at the first instant at or after its row's time (el_port_inputs); a
 * device `out` datum's latest value whose row time has come is what the
 * device's read gives. The host side turned each row's time into that
 * first tick, so here an event applies at the first instant whose tick is
 * not below its own. At every instant (el_port_instant) the program writes
 * the bytes of every item and chart as they are in its memory; the host
 * side writes the trace from them with the host board's own code.
 */
#include "f16_internal.h"
#include "f16p.h"
#include "el_model.h"

#define EVENT_VALUE_MAX 4u

static uint32_t end_tick;     /* the first tick not run */
static bool pending;          /* an event is read and waits for its tick */
static uint32_t ev_tick;
static uint16_t ev_item, ev_first, ev_n;
static uint8_t ev_size;
static uint8_t ev_value[EVENT_VALUE_MAX];

static uint32_t in_u32(void)
{
    uint32_t v = 0u;
    uint8_t i;
    for (i = 0u; i < 4u; i++) {
        v |= (uint32_t)(uint8_t)el_f16p_in() << (8u * i);
    }
    return v;
}

static uint16_t in_u16(void)
{
    uint16_t lo = (uint8_t)el_f16p_in();
    return (uint16_t)(lo | (uint16_t)((uint16_t)(uint8_t)el_f16p_in() << 8));
}

static uint8_t type_size(uint8_t type)
{
    switch (type) {
    case EL_T_BOOL:
    case EL_T_I8:
    case EL_T_U8:
        return 1u;
    case EL_T_I16:
    case EL_T_U16:
        return 2u;
    default:
        return 4u;
    }
}

static void next_event(void)
{
    uint8_t i;
    pending = false;
    if (el_f16p_in() != 'e') { /* the end of the stream */
        return;
    }
    ev_tick = in_u32();
    ev_item = in_u16();
    ev_first = in_u16();
    ev_n = in_u16();
    ev_size = (uint8_t)el_f16p_in();
    for (i = 0u; i < ev_size && i < EVENT_VALUE_MAX; i++) {
        ev_value[i] = (uint8_t)el_f16p_in();
    }
    pending = ev_item < el_item_count && ev_size == type_size(el_items[ev_item].type);
}

void el_f16p_sim_init(void)
{
    uint16_t u16 = 0x1234u;
    uint32_t u32 = 0x12345678UL;
    float f = 1.5f;
    /* "EL16" starts both streams. */
    el_f16p_out((uint8_t)'E');
    el_f16p_out((uint8_t)'L');
    el_f16p_out((uint8_t)'1');
    el_f16p_out((uint8_t)'6');
    el_f16p_out_bytes(&u16, 2u);
    el_f16p_out_bytes(&u32, 4u);
    el_f16p_out_bytes(&f, 4u);
    end_tick = 0u;
    if (el_f16p_in() != 'E' || el_f16p_in() != 'L' || el_f16p_in() != '1' || el_f16p_in() != '6') {
        return; /* no stream: the run ends at once (the host side reports it) */
    }
    end_tick = in_u32();
    next_event();
}

bool el_f16p_sim_run_on(uint32_t tick)
{
    return tick < end_tick;
}

static void apply(void)
{
    const el_item_t *it = &el_items[ev_item];
    uint16_t k;
    uint8_t b;
    for (k = 0u; k < ev_n; k++) {
        uint16_t element = (uint16_t)(ev_first + k);
        uint8_t *dst;
        if (it->kind == EL_K_DEV_OUT) {
            dst = &el_f16p_mailbox[el_f16p_mail_at[ev_item] + element * ev_size];
            el_f16p_mail_set[el_f16p_set_at[ev_item] + element] = 1u;
        } else {
            dst = (uint8_t *)it->addr + element * ev_size;
        }
        for (b = 0u; b < ev_size; b++) {
            dst[b] = ev_value[b];
        }
    }
}

void el_f16p_sim_inputs(el_tick_t tick)
{
    while (pending && (int32_t)((uint32_t)tick - ev_tick) >= 0) {
        apply();
        next_event();
    }
}

void el_f16p_sim_instant(el_tick_t tick)
{
    uint32_t t = (uint32_t)tick;
    uint16_t i;
    uint8_t c;
    el_f16p_out((uint8_t)'I');
    el_f16p_out_bytes(&t, 4u);
    for (i = 0u; i < el_item_count; i++) {
        el_f16p_out_bytes(el_items[i].addr, (uint16_t)(type_size(el_items[i].type) * el_items[i].count));
    }
    for (c = 0u; c < el_chart_count; c++) {
        el_f16p_out_bytes(el_charts[c].active, el_charts[c].step_count);
    }
}

void el_f16p_sim_end(void)
{
    el_f16p_out((uint8_t)'X');
}

/* ---- simulated devices ---- */

void el_sim_open(uint8_t device)
{
    (void)device;
}

void el_sim_close(uint8_t device)
{
    (void)device;
}

void el_sim_start(uint8_t device)
{
    (void)device;
}

void el_sim_stop(uint8_t device)
{
    (void)device;
}

void el_sim_read(uint8_t device)
{
    uint16_t i, k;
    uint8_t b;
    for (i = 0u; i < el_item_count; i++) {
        const el_item_t *it = &el_items[i];
        uint8_t size = type_size(it->type);
        if (it->kind != EL_K_DEV_OUT || it->device != device) {
            continue;
        }
        for (k = 0u; k < it->count; k++) {
            if (el_f16p_mail_set[el_f16p_set_at[i] + k] != 0u) {
                const uint8_t *src = &el_f16p_mailbox[el_f16p_mail_at[i] + k * size];
                uint8_t *dst = (uint8_t *)it->addr + k * size;
                for (b = 0u; b < size; b++) {
                    dst[b] = src[b];
                }
            }
        }
    }
}

void el_sim_write(uint8_t device)
{
    (void)device;
}
