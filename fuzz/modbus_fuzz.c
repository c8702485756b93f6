/* libFuzzer target over the Modbus slave's request parsers (runtime_c/
 * el_modbus.c) and the persistence records it writes (el_persist.c), with
 * a hand-written register map holding every item type, holes and a far
 * explicit address. Build and run (tests/service/test_service_fuzz.py does):
 *
 *   clang -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all \
 *       -Iruntime_c fuzz/modbus_fuzz.c runtime_c/el_modbus.c runtime_c/el_service.c \
 *       runtime_c/el_persist.c runtime_c/el_crc16.c -o modbus_fuzz
 *   ./modbus_fuzz -runs=100000 CORPUS_COPY fuzz/modbus_corpus
 *
 * The first byte of an input chooses what the rest is:
 *   0  an RTU byte stream (0xFF 0xFE pairs stand for t3.5 silences; bit 2 of
 *      the first byte: early framing, as on a pty)
 *   1  one RTU frame, the CRC appended here (else the fuzzer would never get
 *      past the check), to our unit or, by bit 3, broadcast
 *   2  a TCP byte stream, split into ADUs by the MBAP framing
 *   3  one PDU for el_mb_pdu, in a buffer of exactly its size
 *   4  the non-volatile storage's bytes, then loading the persist params
 *
 * Invariants checked after every input (abort on violation): every item
 * holds a value of its type and range; replies are at most one ADU, RTU
 * replies carry a good CRC and our unit, TCP replies echo the MBAP header
 * with a length that matches; exceptions use fc | 0x80 and codes 1..4; a
 * broadcast is never answered.
 */
#include "el_crc16.h"
#include "el_model.h"
#include "el_modbus.h"
#include "el_persist.h"
#include "el_port.h"
#include "el_service.h"

#include <stdlib.h>
#include <string.h>

#define UNIT 7u
#define NV_SIZE 256u

static bool v_coil0, v_coil1, v_di0;
static int8_t v_i8;
static uint8_t v_u8;
static int16_t v_i16, v_far;
static uint16_t v_u16, v_in16;
static int32_t v_i32;
static uint32_t v_u32, v_time;
static float v_f32, v_in_f32;

/* float32 -10.0 and 100.0 as IEEE bits */
#define F_M10 0xc1200000UL
#define F_100 0x42c80000UL

static const el_svc_entry_t entries[] = {
    {"coil0", (void *)&v_coil0, 0UL, 0UL, 0u, 0u, 0u, EL_T_BOOL, EL_SVC_COIL, EL_SVC_F_RW},
    {"coil1", (void *)&v_coil1, 0UL, 0UL, 1u, 0x1111u, 0u, EL_T_BOOL, EL_SVC_COIL, EL_SVC_F_RW | EL_SVC_F_PERSIST},
    {"di0", (void *)&v_di0, 0UL, 0UL, 5u, 0u, 0u, EL_T_BOOL, EL_SVC_DISCRETE, 0u},
    {"i8", (void *)&v_i8, 0xffffff9cUL, 100UL, 0u, 0x2222u, 1u, EL_T_I8, EL_SVC_HOLDING,
     EL_SVC_F_RW | EL_SVC_F_PERSIST | EL_SVC_F_RANGE},
    {"u8", (void *)&v_u8, 0UL, 200UL, 1u, 0u, 0u, EL_T_U8, EL_SVC_HOLDING, EL_SVC_F_RW | EL_SVC_F_RANGE},
    {"i16", (void *)&v_i16, 0xfffffc18UL, 1000UL, 2u, 0x3333u, 2u, EL_T_I16, EL_SVC_HOLDING,
     EL_SVC_F_RW | EL_SVC_F_PERSIST | EL_SVC_F_RANGE},
    {"u16", (void *)&v_u16, 0UL, 0UL, 3u, 0u, 0u, EL_T_U16, EL_SVC_HOLDING, EL_SVC_F_RW},
    {"i32", (void *)&v_i32, 0xffe17b80UL, 2000000UL, 4u, 0x4444u, 3u, EL_T_I32, EL_SVC_HOLDING,
     EL_SVC_F_RW | EL_SVC_F_PERSIST | EL_SVC_F_RANGE},
    {"u32", (void *)&v_u32, 0UL, 0UL, 6u, 0u, 0u, EL_T_U32, EL_SVC_HOLDING, EL_SVC_F_RW},
    {"f32", (void *)&v_f32, F_M10, F_100, 8u, 0x5555u, 4u, EL_T_F32, EL_SVC_HOLDING,
     EL_SVC_F_RW | EL_SVC_F_PERSIST | EL_SVC_F_RANGE},
    {"time", (void *)&v_time, 100UL, 60000UL, 10u, 0x6666u, 5u, EL_T_TIME, EL_SVC_HOLDING,
     EL_SVC_F_RW | EL_SVC_F_PERSIST | EL_SVC_F_RANGE},
    {"far", (void *)&v_far, 0UL, 0UL, 65534u, 0u, 0u, EL_T_I16, EL_SVC_HOLDING, EL_SVC_F_RW}, /* 65534: the last two */
    {"in16", (void *)&v_in16, 0UL, 0UL, 0u, 0u, 0u, EL_T_U16, EL_SVC_INPUT, 0u},
    {"in_f32", (void *)&v_in_f32, 0UL, 0UL, 2u, 0u, 0u, EL_T_F32, EL_SVC_INPUT, 0u},   /* hole at 1 */
};
#define COUNT ((uint16_t)(sizeof entries / sizeof entries[0]))
/* coils 0, 1; discrete 2; holding 3..11; input 12, 13 */
static const uint16_t order[COUNT] = {0u, 1u, 2u, 3u, 4u, 5u, 6u, 7u, 8u, 9u, 10u, 11u, 12u, 13u};
static el_svc_nv_t nv_state[6];
static const el_svc_map_t map = {
    entries, COUNT, order, {0u, 2u, 3u, 12u}, {2u, 1u, 9u, 2u}, nv_state, 6u, 16u,
    "EasyLab", "fuzz", "Fuzz target", "0.1.0", "0x12345678", 0x12345678UL,
};

/* ---- the port's non-volatile storage, in memory ---- */
static uint8_t nv[NV_SIZE];

bool el_port_nv_read(uint16_t offset, void *data, uint16_t size)
{
    if ((uint32_t)offset + size > NV_SIZE)
        abort(); /* the layout never leaves the store */
    memcpy(data, nv + offset, size);
    return true;
}

bool el_port_nv_write(uint16_t offset, const void *data, uint16_t size)
{
    if ((uint32_t)offset + size > NV_SIZE)
        abort();
    memcpy(nv + offset, data, size);
    return true;
}

static void reset_values(void)
{
    v_coil0 = v_coil1 = v_di0 = false;
    v_i8 = -5;
    v_u8 = 7;
    v_i16 = -300;
    v_far = 7;
    v_u16 = 40000u;
    v_in16 = 1u;
    v_i32 = -100000L;
    v_u32 = 3000000000UL;
    v_time = 2000UL;
    v_f32 = 1.5f;
    v_in_f32 = 2.5f;
}

static void check_items(void)
{
    uint16_t id;
    for (id = 0; id < COUNT; id++) {
        el_svc_value_t v;
        if (el_service_get(id, &v) != EL_SVC_OK || el_service_check(id, &v) != EL_SVC_OK)
            abort();
    }
}

static void check_pdu_reply(const uint8_t *req, uint16_t req_len, const uint8_t *resp, uint16_t n)
{
    if (n > EL_MB_PDU_MAX)
        abort();
    if (n == 0u)
        return;
    if ((resp[0] & 0x80u) != 0u) {
        if (n != 2u || resp[1] < 1u || resp[1] > 4u || (req_len > 0u && resp[0] != (uint8_t)(req[0] | 0x80u)))
            abort();
    }
}

static void feed_rtu(el_mb_rtu_t *rtu, uint8_t byte)
{
    if (el_mb_rtu_byte(rtu, byte)) {
        uint16_t n = el_mb_rtu_reply(rtu);
        if (n > EL_MB_RTU_ADU_MAX || (n > 0u && (el_crc16(rtu->buf, n) != 0u || rtu->buf[0] != UNIT)))
            abort();
    }
}

static void silence_rtu(el_mb_rtu_t *rtu)
{
    if (el_mb_rtu_silence(rtu)) {
        uint16_t n = el_mb_rtu_reply(rtu);
        if (n > EL_MB_RTU_ADU_MAX || (n > 0u && (el_crc16(rtu->buf, n) != 0u || rtu->buf[0] != UNIT)))
            abort();
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static bool started;
    static el_mb_rtu_t rtu;
    uint8_t mode;
    size_t i;

    if (!started) {
        started = true;
        memset(nv, 0xFF, sizeof nv);
        reset_values();
        el_service_init(&map);
    }
    if (size == 0u)
        return 0;
    mode = data[0];
    data++;
    size--;
    switch (mode % 5u) {
    case 0: /* an RTU stream */
        el_mb_rtu_init(&rtu, UNIT, (mode & 4u) != 0u);
        for (i = 0; i < size; i++) {
            if (data[i] == 0xFFu && i + 1u < size && data[i + 1u] == 0xFEu) {
                silence_rtu(&rtu);
                i++;
            } else {
                feed_rtu(&rtu, data[i]);
            }
        }
        silence_rtu(&rtu);
        break;
    case 1: { /* one CRC-valid frame */
        uint8_t frame[300];
        uint16_t crc, n;
        if (size + 3u > sizeof frame)
            return 0;
        frame[0] = (mode & 8u) != 0u ? 0u : UNIT;
        memcpy(frame + 1, data, size);
        crc = el_crc16(frame, (uint16_t)(size + 1u));
        frame[size + 1u] = (uint8_t)(crc & 0xFFu);
        frame[size + 2u] = (uint8_t)(crc >> 8);
        el_mb_rtu_init(&rtu, UNIT, (mode & 4u) != 0u);
        for (i = 0; i < size + 3u; i++)
            (void)el_mb_rtu_byte(&rtu, frame[i]);
        if (!el_mb_rtu_silence(&rtu))
            abort();
        n = el_mb_rtu_reply(&rtu);
        if (n > EL_MB_RTU_ADU_MAX || (n > 0u && (el_crc16(rtu.buf, n) != 0u || rtu.buf[0] != UNIT)))
            abort();
        if (frame[0] == 0u && n != 0u)
            abort(); /* a broadcast is never answered */
        break;
    }
    case 2: { /* a TCP stream */
        uint8_t *stream = (uint8_t *)malloc(size ? size : 1u);
        uint8_t adu[EL_MB_TCP_ADU_MAX];
        size_t at = 0;
        if (stream == NULL)
            return 0;
        memcpy(stream, data, size);
        while (at < size) {
            uint16_t avail = (uint16_t)(size - at > 0xFFFFu ? 0xFFFFu : size - at);
            int16_t want = el_mb_tcp_adu_length(stream + at, avail);
            uint16_t r;
            if (want <= 0 || (uint16_t)want > avail)
                break; /* more needed, or the connection is closed */
            if ((uint16_t)want > EL_MB_TCP_ADU_MAX)
                abort();
            memcpy(adu, stream + at, (size_t)want);
            r = el_mb_tcp_reply(adu, (uint16_t)want);
            if (r == 0u || r > EL_MB_TCP_ADU_MAX || memcmp(adu, stream + at, 4) != 0 || adu[6] != stream[at + 6u] ||
                (uint16_t)((adu[4] << 8) | adu[5]) != r - 6u)
                abort();
            check_pdu_reply(stream + at + 7, (uint16_t)(want - 7), adu + 7, (uint16_t)(r - 7u));
            at += (size_t)want;
        }
        free(stream);
        break;
    }
    case 3: { /* one PDU, in a buffer of exactly its size */
        uint8_t *req, resp[EL_MB_PDU_MAX];
        uint16_t n;
        if (size > EL_MB_PDU_MAX)
            return 0;
        req = (uint8_t *)malloc(size ? size : 1u);
        if (req == NULL)
            return 0;
        memcpy(req, data, size);
        n = el_mb_pdu(req, (uint16_t)size, resp, (mode & 8u) != 0u);
        if ((mode & 8u) != 0u && n != 0u)
            abort();
        check_pdu_reply(req, (uint16_t)size, resp, n);
        free(req);
        break;
    }
    default: /* storage contents, then loading */
        memcpy(nv, data, size < NV_SIZE ? size : NV_SIZE);
        el_persist_load(&map);
        break;
    }
    check_items();
    return 0;
}
