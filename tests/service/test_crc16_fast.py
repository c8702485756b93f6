"""runtime_c/el_crc16.c's table-driven CRC (el_crc16_fast, el_crc16_fast_byte,
which the Modbus slave uses) against the bitwise one (el_crc16_update, the
reference the debug protocol and the Python side share): the same CRC for
every byte value after many starting CRCs, and over frames of every length
up to an RTU ADU. A C harness, built with UBSan."""

from __future__ import annotations

from svc_testlib import run_runtime_harness

HARNESS = r"""
#include "el_crc16.h"
#include <stdio.h>

int main(void)
{
    static uint8_t frame[256];
    uint32_t crc, x = 12345u;
    uint16_t len, b;
    int failures = 0;
    const uint8_t check[9] = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
    if (el_crc16_fast(EL_CRC16_INIT, check, 9u) != 0x4B37u)
        failures++;
    for (crc = 0u; crc < 0x10000u; crc += 257u) {
        for (b = 0u; b < 256u; b++) {
            uint8_t byte = (uint8_t)b;
            uint16_t want = el_crc16_update((uint16_t)crc, &byte, 1u);
            if (el_crc16_fast((uint16_t)crc, &byte, 1u) != want || el_crc16_fast_byte((uint16_t)crc, byte) != want)
                failures++;
        }
    }
    for (len = 0u; len <= 256u; len++) {
        uint16_t i, running = EL_CRC16_INIT;
        for (i = 0u; i < len; i++) {
            x = x * 1103515245u + 12345u;
            frame[i] = (uint8_t)(x >> 16);
        }
        for (i = 0u; i < len; i++)
            running = el_crc16_fast_byte(running, frame[i]);
        if (el_crc16_fast(EL_CRC16_INIT, frame, len) != el_crc16(frame, len) || running != el_crc16(frame, len))
            failures++;
    }
    printf("failures: %d\n", failures);
    return failures != 0;
}
"""


def test_the_table_driven_crc_is_the_bitwise_crc(tmp_path):
    proc = run_runtime_harness(tmp_path, "crc16_fast", HARNESS, ("el_crc16.c",), "undefined")
    assert proc.returncode == 0 and proc.stdout == "failures: 0\n", proc.stdout + proc.stderr
