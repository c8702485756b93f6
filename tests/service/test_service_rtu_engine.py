"""The RTU receiver of runtime_c/el_modbus.c driven as an MCU port drives it
(bytes from the receive interrupt, silences from a t3.5 timer), with a
simulated clock: no early framing, a frame ends only at a silence; bytes
that come while a frame waits for its reply are dropped; an overflow drops
the whole frame; el_mb_rtu_poll over a port of bytes and silence marks.
A C harness, built with ASan and UBSan."""

from __future__ import annotations

from svc_testlib import run_runtime_harness

HARNESS = r"""
#include "el_crc16.h"
#include "el_model.h"
#include "el_modbus.h"
#include "el_service.h"
#include <stdio.h>
#include <string.h>

bool el_port_nv_read(uint16_t o, void *d, uint16_t n) { (void)o; memset(d, 0xFF, n); return true; }
bool el_port_nv_write(uint16_t o, const void *d, uint16_t n) { (void)o; (void)d; (void)n; return true; }

static int16_t value = 7;
static const el_svc_entry_t entries[1] = {{"v", (void *)&value, 0UL, 0UL, 0u, 0u, 0u, EL_T_I16, EL_SVC_HOLDING,
                                           EL_SVC_F_RW}};
static const uint16_t order[1] = {0u};
static const el_svc_map_t map = {entries, 1u, order, {0u, 0u, 0u, 1u}, {0u, 0u, 1u, 0u}, (el_svc_nv_t *)0, 0u, 0u,
                                 "EasyLab", "t", "t", "0", "0x0", 0UL};
static int failures;
#define CHECK(c) do { if (!(c)) { printf("line %d: %s\n", __LINE__, #c); failures++; } } while (0)

static uint16_t frame(uint8_t *f, uint8_t unit, uint8_t fc, uint16_t a, uint16_t b)
{
    uint16_t crc;
    f[0] = unit; f[1] = fc; f[2] = (uint8_t)(a >> 8); f[3] = (uint8_t)a; f[4] = (uint8_t)(b >> 8); f[5] = (uint8_t)b;
    crc = el_crc16(f, 6u);
    f[6] = (uint8_t)crc; f[7] = (uint8_t)(crc >> 8);
    return 8u;
}

/* A port of events for el_mb_rtu_poll. */
static int16_t events[64];
static int nevents, next_event;
static uint8_t sent[300];
static uint16_t sent_len;
static int16_t port_getc(void) { return next_event < nevents ? events[next_event++] : EL_MB_NONE; }
static void port_send(const uint8_t *adu, uint16_t len) { memcpy(sent, adu, len); sent_len = len; }

int main(void)
{
    static el_mb_rtu_t rtu;
    uint8_t f[8];
    uint16_t i, n;
    el_service_init(&map);

    /* Timed port: a complete, CRC-valid request does not end the frame. */
    el_mb_rtu_init(&rtu, 5u, false);
    frame(f, 5u, 0x03u, 0u, 1u);
    for (i = 0; i < 8u; i++)
        CHECK(!el_mb_rtu_byte(&rtu, f[i]));
    CHECK(el_mb_rtu_silence(&rtu));
    /* Bytes while the frame waits for its reply are dropped. */
    CHECK(!el_mb_rtu_byte(&rtu, 0x55u));
    n = el_mb_rtu_reply(&rtu);
    CHECK(n == 7u && rtu.buf[0] == 5u && rtu.buf[1] == 3u && rtu.buf[2] == 2u && rtu.buf[4] == 7u);
    CHECK(el_crc16(rtu.buf, n) == 0u);
    CHECK(!el_mb_rtu_silence(&rtu)); /* nothing pending */

    /* Two requests without a silence between them are one bad frame. */
    for (i = 0; i < 16u; i++)
        (void)el_mb_rtu_byte(&rtu, f[i % 8u]);
    CHECK(el_mb_rtu_silence(&rtu));
    CHECK(el_mb_rtu_reply(&rtu) == 0u && rtu.bad_frames == 1u);

    /* Overflow: 300 bytes, then a silence: dropped; the next frame is fine. */
    for (i = 0; i < 300u; i++)
        (void)el_mb_rtu_byte(&rtu, (uint8_t)i);
    CHECK(el_mb_rtu_silence(&rtu));
    CHECK(el_mb_rtu_reply(&rtu) == 0u && rtu.bad_frames == 2u);
    for (i = 0; i < 8u; i++)
        (void)el_mb_rtu_byte(&rtu, f[i]);
    CHECK(el_mb_rtu_silence(&rtu) && el_mb_rtu_reply(&rtu) == 7u);

    /* Another unit: no reply, not counted as bad. */
    frame(f, 6u, 0x03u, 0u, 1u);
    for (i = 0; i < 8u; i++)
        (void)el_mb_rtu_byte(&rtu, f[i]);
    CHECK(el_mb_rtu_silence(&rtu) && el_mb_rtu_reply(&rtu) == 0u && rtu.bad_frames == 2u);

    /* Early mode: the frame ends at its last byte. */
    el_mb_rtu_init(&rtu, 5u, true);
    frame(f, 5u, 0x06u, 0u, 9u);
    for (i = 0; i < 7u; i++)
        CHECK(!el_mb_rtu_byte(&rtu, f[i]));
    CHECK(el_mb_rtu_byte(&rtu, f[7]));
    CHECK(el_mb_rtu_reply(&rtu) == 8u && value == 9);

    /* el_mb_rtu_poll over a port: garbage, silence, request, silence. */
    el_mb_rtu_init(&rtu, 5u, false);
    events[nevents++] = 0x12; events[nevents++] = 0x34; events[nevents++] = EL_MB_SILENCE;
    frame(f, 5u, 0x03u, 0u, 1u);
    for (i = 0; i < 8u; i++)
        events[nevents++] = f[i];
    events[nevents++] = EL_MB_SILENCE;
    el_mb_rtu_poll(&rtu, &(el_mb_rtu_port_t){port_getc, port_send});
    CHECK(sent_len == 7u && sent[4] == 9u && rtu.bad_frames == 1u);
    printf("failures: %d\n", failures);
    return failures != 0;
}
"""


def test_rtu_receiver_with_a_simulated_clock(tmp_path):
    proc = run_runtime_harness(tmp_path, "rtu_engine", HARNESS,
                               ("el_modbus.c", "el_service.c", "el_persist.c", "el_crc16.c"), "address,undefined")
    assert proc.returncode == 0 and proc.stdout.endswith("failures: 0\n"), proc.stdout + proc.stderr
