"""The port contract (runtime_c/el_port.h), one test program for every
port: port_contract.c on the host board (a process) and on the AVR board
(the ATmega328P and the ATmega2560 in simavr). Among others it catches a
port whose critical sections do the opposite of what they say (reactor-c's
Arduino port had interrupt enable and disable inverted)."""

from __future__ import annotations

import subprocess
import tomllib

import pytest

from avr_testlib import HERE, ROOT

RUNTIME = ROOT / "runtime_c"
HOST = ROOT / "boards" / "host"
AVR = ROOT / "boards" / "avr"
CONTRACT = HERE / "port_contract.c"
CHECKS = ["init", "tick_period", "real_tick", "late_tick", "irq_nesting", "irq_masks", "idle", "resync", "nv",
          "instants"]

# The harness's view of the contract program (sim/sim_model.h): one item, no
# devices; nothing is traced, UART0 carries the report.
SIM_MODEL = """#include "sim_model.h"
static uint16_t m_failures[1];
const char el_model_name[] = "port_contract";
const uint32_t el_program_id = 0x0c0de001UL;
const uint32_t el_tick_us = 1000UL;
const uint32_t el_hyperperiod_ticks = 1UL;
const el_item_t el_items[1] = { { "failures", m_failures, EL_T_U16, EL_K_VAR, EL_NO_DEVICE, 1u } };
const uint16_t el_item_count = 1u;
const el_device_t el_devices[1] = { { "", "" } };
const uint8_t el_device_count = 0u;
const el_chart_t el_charts[1] = { { "", 0u, (const char *const *)0, (const uint8_t *)0 } };
const uint8_t el_chart_count = 0u;
const sim_addr_t sim_item_addr[1] = { { 0xffffu, 2u } };
const sim_addr_t sim_chart_addr[1] = { { 0xffffu, 0u } };
const uint16_t sim_tick_addr = 0xffffu;
const sim_hw_t sim_hw[1] = { { 0xffffu, SIM_HW_NONE, 0u, 0u, 0UL } };
const uint16_t sim_hw_count = 0u;
const sim_pin_t sim_pins[1] = { { 0, 0u, SIM_PIN_LEVEL, 0u, 0u, 0u, "", "" } };
const uint16_t sim_pin_count = 0u;
const char sim_uarts[] = "%(uarts)s";
const char sim_mcu[] = "%(mcu)s";
const uint32_t sim_clock_hz = 16000000UL;
const char sim_elf_default[] = "%(elf)s";
const uint32_t sim_nv_size = %(eeprom)dUL;
"""


def parse_report(text: str) -> dict[str, str]:
    results = {}
    for line in text.splitlines():
        if line.startswith("ok "):
            results[line[3:]] = "ok"
        elif line.startswith("FAIL "):
            name, _, detail = line[5:].partition(": ")
            results[name] = detail
    assert text.rstrip().endswith("failed"), text
    return results


def test_the_host_port_passes_the_contract(tmp_path):
    board = tomllib.loads((HOST / "board.toml").read_text())
    runtime = [p for p in sorted(RUNTIME.glob("*.c")) if p.name != "el_dispatch.c" and not p.name.startswith("el_debug")]
    exe = tmp_path / "contract"
    cmd = ["gcc", *board["toolchain"]["cflags"], "-DEL_RELEASE=1", f"-I{RUNTIME}", f"-I{HOST}", "-o", str(exe),
           str(CONTRACT), *[str(HOST / s) for s in board["sources"]], *map(str, runtime),
           *board["toolchain"].get("ldflags", [])]
    subprocess.run(cmd, check=True, capture_output=True, text=True)
    proc = subprocess.run([str(exe)], capture_output=True, text=True, timeout=60)
    results = parse_report(proc.stdout)
    assert results == {c: "ok" for c in CHECKS}, proc.stdout
    assert proc.returncode == 0


@pytest.mark.parametrize("mcu", ["atmega328p", "atmega2560"])
def test_the_avr_port_passes_the_contract_in_simavr(tmp_path, mcu):
    from easylab.avrgen import CONFIG_VERSION, configure, mcus, tick_timer
    from easylab.boards import load_board

    board = configure(load_board("avr"), mcu)
    part = mcus(board)[mcu]
    t = tick_timer(1000, 16_000_000)
    (tmp_path / "el_avr_config.h").write_text(f"""#define EL_AVR_CONFIG_VERSION {CONFIG_VERSION}
#define EL_AVR_MCU_NAME "{mcu}"
#define EL_AVR_NV_SIZE {part.eeprom}u
#define EL_AVR_TICK_PRESCALE {t.prescale}u
#define EL_AVR_TICK_CS {t.cs}u
#define EL_AVR_TICK_OCR {t.ocr}u
#define EL_AVR_TICK_ISRS {t.isrs}u
#define EL_AVR_CLOCK_KHZ {16_000_000 // t.prescale // 1000}u
#define EL_AVR_WDTO WDTO_2S
""")
    (tmp_path / "el_avr_devices.h").write_text("/* no devices */\n")
    elf = tmp_path / "contract.elf"
    sources = [CONTRACT, AVR / "avr_port.c", AVR / "avr_nv.c", AVR / "avr_uart.c"]
    cmd = ["avr-gcc", *board.cflags, "-DEL_RELEASE=1", f"-I{tmp_path}", f"-I{RUNTIME}", f"-I{AVR}",
           "-o", str(elf), *map(str, sources), *board.ldflags]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    # The harness, for an empty model on this MCU.
    sim_dir = AVR / "sim"
    (tmp_path / "sim_model.c").write_text(SIM_MODEL % {"uarts": "".join(map(str, sorted(part.uart))), "mcu": mcu,
                                                      "elf": elf, "eeprom": part.eeprom})
    spec = board.raw["simulator"]
    pc = subprocess.run(["pkg-config", "--cflags", "--libs", "simavr"], capture_output=True, text=True, check=True)
    harness = tmp_path / "contract-sim"
    cmd = ["gcc", *spec["cflags"], f"-I{sim_dir}", f"-I{HOST}", f"-I{RUNTIME}", "-o", str(harness),
           *[str(AVR / s) for s in spec["sources"]], str(tmp_path / "sim_model.c"), *pc.stdout.split(),
           *spec["ldflags"]]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    report = tmp_path / "uart0.txt"
    proc = subprocess.run([str(harness), "--fast", "--uart0", f"file:{report}", "--cycles", "100000000"],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    results = parse_report(report.read_text())
    assert results == {c: "ok" for c in CHECKS}, report.read_text()
