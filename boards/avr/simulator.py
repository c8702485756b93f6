"""The AVR board's simulator: the simavr harness of sim/ compiled with one
build's tables (sim_model.c: the items' names, types and RAM addresses,
how device data reach the hardware, the pins to trace), against Debian's
libsimavr (docs/boards.md, "Simulation")."""

from __future__ import annotations

import subprocess
from easylab.codegen.c_syntax import c_comment
from pathlib import Path

from easylab.board.cbuild import require_tool, run, write_files
from easylab.board.registry import load_board
from easylab.board.simtables import (c_string, chip_hardware_row, chip_table, no_model_tables,
                                     ram_tables, sim_table, state_tables, trace_tables)
from easylab.board.stimulus_columns import driven_items, unread_table
from easylab.core.errors import BuildError
from easylab.core.paths import data_dir, runtime_dir
from easylab.ir.program import Program

from .devices import device_views
from .parts import Mcu

# Data-space addresses of the registers the harness watches (avr-libc's
# io headers; the same on both parts where both have the register).
_IO = {
    "atmega328p": {"TCCR0A": 0x44, "OCR0A": 0x47, "OCR0B": 0x48, "TCCR1A": 0x80, "OCR1AL": 0x88, "OCR1BL": 0x8A,
                   "TCCR2A": 0xB0, "OCR2A": 0xB3, "OCR2B": 0xB4},
    "atmega2560": {"TCCR0A": 0x44, "OCR0A": 0x47, "OCR0B": 0x48, "TCCR1A": 0x80, "OCR1AL": 0x88, "OCR1BL": 0x8A,
                   "OCR1CL": 0x8C, "TCCR2A": 0xB0, "OCR2A": 0xB3, "OCR2B": 0xB4, "TCCR3A": 0x90, "OCR3AL": 0x98,
                   "OCR3BL": 0x9A, "OCR3CL": 0x9C, "TCCR4A": 0xA0, "OCR4AL": 0xA8, "OCR4BL": 0xAA, "OCR4CL": 0xAC,
                   "TCCR5A": 0x120, "OCR5AL": 0x128, "OCR5BL": 0x12A, "OCR5CL": 0x12C},
}
TICK_SYMBOL = "el_avr_sim_tick"


def ram_symbols(nm: str, elf: Path) -> dict[str, tuple[int, int]]:
    """name -> (data address, size) of the ELF's RAM symbols."""
    out = run([nm, "-S", "--defined-only", str(elf)], "avr-nm", "binutils-avr").stdout
    syms = {}
    for line in out.splitlines():
        parts = line.split()
        if len(parts) == 4:
            addr, size, _kind, name = parts
            a = int(addr, 16)
            if 0x800000 <= a < 0x810000:
                syms[name] = (a - 0x800000, int(size, 16))
    return syms


def _hardware_rows(program: Program, views: dict, board_name: str) -> list[tuple[str, int, str]]:
    """sim_hw: how each device datum reaches the hardware the harness drives
    (the harness runs the std chip models too: easylab.board.simtables);
    each row with its item id and kind (which data the harness drives:
    stimulus_columns.driven_items)."""
    rows = []
    for it in program.items:
        if it.device is None:
            continue
        chip = chip_hardware_row(program, it, board_name)  # a chip on a bus, whatever drives the device
        if chip is not None:
            rows.append((chip, it.id, "SIM_HW_CHIP"))
            continue
        if it.device not in views:  # a device that runs handlers from the model's folder
            rows.append((f"    {{ {it.id}u, SIM_HW_NONE, 0u, 0u, 0UL }}, /* {it.name} (handlers of the model) */",
                         it.id, "SIM_HW_NONE"))
            continue
        v = views[it.device]
        h = v.hw
        kind, a, b, c = "SIM_HW_NONE", 0, 0, 0
        if v.driver == "analog_in":
            kind, a = "SIM_HW_ADC", h["adc"]
        elif v.driver in ("digital_in", "digital_out"):
            kind = "SIM_HW_PIN_IN" if v.driver == "digital_in" else "SIM_HW_PIN_OUT"
            a, b = ord(h["pin"][1]), int(h["pin"][2])
        elif v.driver == "line_camera":
            kind, a, c = "SIM_HW_CAMERA", h["uart"], h["baud"]
        elif v.driver == "encoder":
            kind = "SIM_HW_ENCODER"
            a = ord(h["pin_a"][1]) << 8 | int(h["pin_a"][2])
            b = ord(h["pin_b"][1]) << 8 | int(h["pin_b"][2])
        elif v.driver in ("pwm_out", "motor"):
            kind = "SIM_HW_PWM"
        rows.append((f"    {{ {it.id}u, {kind}, {a}u, {b}u, {c}UL }}, /* {it.name} ({v.driver}) */", it.id, kind))
    return rows


def _pin_rows(mcu: Mcu, views: dict) -> list[str]:
    """sim_pins: every claimed pin, with what it is."""
    pins = []
    for v in views.values():
        h = v.hw
        if v.driver in ("digital_in", "digital_out"):
            pins.append((h["pin"], "SIM_PIN_LEVEL", 0, "", v.path))
        elif v.driver in ("pwm_out", "motor"):
            p = h["pwm"]
            pins.append((p["pin"], "SIM_PIN_PWM", p["timer"], p["channel"], v.path))
            if v.driver == "motor":
                pins.append((h["dir"], "SIM_PIN_LEVEL", 0, "", v.path + " (direction)"))
        elif v.driver == "encoder":
            pins.append((h["pin_a"], "SIM_PIN_LEVEL", 0, "", v.path + " (A)"))
            pins.append((h["pin_b"], "SIM_PIN_LEVEL", 0, "", v.path + " (B)"))
    rows = []
    for pin, kind, timer, ch, what in pins:
        ocr = tccra = 0
        if kind == "SIM_PIN_PWM":
            ocr = _IO[mcu.name][f"OCR{timer}{ch}L" if timer in mcu.wide_timers else f"OCR{timer}{ch}"]
            tccra = _IO[mcu.name][f"TCCR{timer}A"]
        com = {"A": 7, "B": 5, "C": 3}.get(ch, 0)
        rows.append(f"    {{ '{pin[1]}', {pin[2]}u, {kind}, 0x{ocr:04x}u, 0x{tccra:04x}u, {com}u, {c_string(pin)}, "
                    f"{c_string(what)} }},")
    return rows


def sim_model_source(program: Program, board, elf: Path) -> str:
    """The harness's view of one build (sim/sim_model.h): the trace tables,
    the RAM addresses, the hardware behind device data, the pins."""
    mcu = board.part
    views = {v.id: v for v in device_views(program, board)}
    lines = [f"/* Generated by EasyLab: the simavr harness's tables for model \"{c_comment(program.name)}\" on the "
             f"{mcu.name}. */", "#include \"sim_model.h\"", ""]
    lines += trace_tables(program)
    symbols = ram_symbols(board.description.toolchain.tool("nm", "avr-nm"), elf)
    lines += ram_tables(program, symbols, TICK_SYMBOL, str(elf))
    lines += state_tables(program, board.name, symbols, str(elf))
    lines.append(f"const uint8_t sim_tick_size = {symbols.get(TICK_SYMBOL, (0, 4))[1]}u;")
    hardware = _hardware_rows(program, views, board.name)
    lines += sim_table("sim_hw_t", "sim_hw", "sim_hw_count", [row for row, _item, _kind in hardware],
                       "{ 0xffffu, SIM_HW_NONE, 0u, 0u, 0UL }")
    lines += unread_table(program, driven_items([(item, kind) for _row, item, kind in hardware]), "simavr",
                          board.name)
    lines += sim_table("sim_pin_t", "sim_pins", "sim_pin_count", _pin_rows(mcu, views),
                       "{ 0, 0u, SIM_PIN_LEVEL, 0u, 0u, 0u, \"\", \"\" }")
    lines += chip_table(program, pin_number, board.name)
    lines += harness_constants(board, elf)
    return "\n".join(lines) + "\n"


def pin_number(pin: str) -> int:
    """The harness's number of a pin ("PB2": port << 3 | bit), as chip
    models see their chip selects (sim/sim_chips.h)."""
    return (ord(pin[1]) - ord("A")) << 3 | int(pin[2:])


def harness_constants(board, elf: Path) -> list[str]:
    """The part's UARTs, name, clock, EEPROM size and the ELF to load."""
    mcu = board.part
    return [f"const char sim_uarts[] = {c_string(''.join(str(u) for u in sorted(mcu.uart)))};",
            f"const char sim_mcu[] = {c_string(mcu.name)};",
            f"const uint32_t sim_clock_hz = {board.clock_hz}UL;",
            f"const char sim_firmware_default[] = {c_string(str(elf.resolve()))};",
            f"const uint32_t sim_nv_size = {mcu.eeprom}UL;"]


def simulation_warnings(program: Program, board) -> list[str]:
    """What simavr 1.6 does not simulate of this build."""
    mcu = board.part
    notes = []
    for v in device_views(program, board):
        if v.driver == "encoder" and mcu.name == "atmega2560":
            off = [p for p in (v.hw["pin_a"], v.hw["pin_b"]) if p not in mcu.ext_int and not p.startswith("PB")]
            if off:
                notes.append(f"warning: simavr 1.6 simulates the atmega2560's pin-change interrupts on port B "
                             f"only: encoder '{v.path}' on {', '.join(off)} counts nothing in simulation (on a "
                             f"board it does)")
    return notes


def build_harness(board, out_dir: Path, model_source: str, exe: Path,
                  chips: list[tuple[str, str]] = ()) -> Path:
    """Compile the harness of sim/ with one build's tables (``model_source``,
    written as sim_model.c in ``out_dir``) into ``exe``; ``chips``: the
    model's chip models, (file, the EL_CHIP symbol it defines)."""
    spec = board.description.table("simulator")
    cc = spec.get("cc", "gcc")
    require_tool(cc, board.name, "gcc", "simulator's C compiler")
    pc = subprocess.run(["pkg-config", "--cflags", "--libs", spec.get("pkg_config", "simavr")], capture_output=True,
                        text=True)
    if pc.returncode != 0:
        raise BuildError(f"libsimavr is not installed (Debian packages: "
                         f"{spec.get('debian_packages', 'libsimavr-dev')}): {pc.stderr.strip()}")
    [model_c] = write_files(out_dir, {"sim_model.c": model_source})
    folder = board.description.folder
    host = load_board("host").description.folder
    shared = data_dir("sim")  # the harnesses' chip dispatch and the chip-model API
    sources = [folder / s for s in spec.get("sources", [])] + [host / s for s in spec.get("host_sources", [])] \
        + [runtime_dir() / s for s in spec.get("runtime_sources", [])] \
        + [shared / s for s in spec.get("shared_sources", [])] + [model_c]
    flags = [*spec.get("cflags", []), f"-I{folder / 'sim'}", f"-I{shared}", f"-I{host}", f"-I{runtime_dir()}"]
    objects = []
    for k, (chip, symbol) in enumerate(chips):  # each with its own EL_CHIP
        objects.append(out_dir / f"chip{k}.o")
        run([cc, *flags, f"-DEL_CHIP={symbol}", "-c", "-o", str(objects[-1]), str(chip)], "building the simulator")
    run([cc, *flags, "-o", str(exe), *map(str, sources + objects), *pc.stdout.split(), *spec.get("ldflags", [])],
        "building the simulator")
    return exe


def port_program_tables(board, elf: Path) -> str:
    """The harness's tables for a program without a model (the port
    contract program): nothing to trace, no devices; UART 0 carries what
    the program prints."""
    return "\n".join([*no_model_tables("simavr", '{ 0, 0u, SIM_PIN_LEVEL, 0u, 0u, 0u, "", "" }'),
                      *chip_table(None, pin_number),
                      "const uint8_t sim_tick_size = 4u;",
                      *harness_constants(board, elf), ""])
