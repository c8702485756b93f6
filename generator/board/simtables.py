"""The tables a simulator harness compiles in to trace a firmware: the
model's items and charts as the host board's trace code sees them
(runtime_c/el_model.h, over host-side mirrors), and where each lives in
the simulated MCU's RAM. A harness reads the values straight from the
MCU's memory at each instant and writes them with the host board's own
trace code, so its trace files equal the host board's byte for byte.

The chips a harness runs (sim/sim_chips.h: a model's own chip models and
the std ones, :func:`sim_chips`) are generic too: ``sim_chip_table``, and
``SIM_HW_CHIP`` rows that route a device datum's stimulus to its chip.

The address tables use the types of a harness's ``sim_model.h``::

    typedef struct { uint16_t addr; uint16_t size; } sim_addr_t;
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from ..codegen.c_syntax import C_KIND_ENUM, C_TYPE_ENUM, c_string, ident
from ..core.errors import BuildError
from ..core.paths import sim_dir
from ..ir.program import Device, Program
from .claims import parse_claim, parse_select

TYPE_BYTES = {"bool": 1, "int8": 1, "uint8": 1, "int16": 2, "uint16": 2, "int32": 4, "uint32": 4, "float32": 4,
              "time": 4}


def item_symbol(program: Program, item_id: int) -> str:
    """The C name generated code gives an item (codegen.c_model)."""
    it = program.items[item_id]
    return f"el_i{it.id}_{ident(it.name)}"


def chart_symbol(chart_id: int) -> str:
    return f"el_c{chart_id}_active"


def trace_tables(program: Program) -> list[str]:
    """el_model.h's tables (names, types, kinds, devices, charts) over
    host-side mirrors ``m_i<id>`` and ``m_c<id>`` the harness fills."""
    lines = [f"static {it.type.c_name} m_i{it.id}[{it.count}];" for it in program.items]
    for c in program.charts:
        n = max(1, len(c.steps))
        lines.append(f"static uint8_t m_c{c.id}[{n}];")
        lines.append(f"static const char *const m_c{c.id}_steps[{n}] = "
                     f"{{ {', '.join(c_string(s.name) for s in c.steps) or c_string('')} }};")
    lines += ["", f"const char el_model_name[] = {c_string(program.name)};",
              f"const uint32_t el_program_id = 0x{program.program_id:08x}UL;",
              f"const uint32_t el_tick_us = {program.tick_us}UL;",
              f"const uint32_t el_hyperperiod_ticks = {program.hyperperiod}UL;",
              f"const el_item_t el_items[{max(1, len(program.items))}] = {{"]
    for it in program.items:
        dev = it.device if it.device is not None else "EL_NO_DEVICE"
        lines.append(f"    {{ {c_string(it.name)}, m_i{it.id}, {C_TYPE_ENUM[it.type.name]}, {C_KIND_ENUM[it.kind]}, "
                     f"{dev}, {it.count}u }},")
    if not program.items:
        lines.append("    { \"\", 0, 0u, 0u, EL_NO_DEVICE, 0u },")
    lines += ["};", f"const uint16_t el_item_count = {len(program.items)}u;",
              f"const el_device_t el_devices[{max(1, len(program.devices))}] = {{"]
    lines += [f"    {{ {c_string(d.path)}, {c_string(d.driver)} }}," for d in program.devices] \
        or ["    { \"\", \"\" },"]
    lines += ["};", f"const uint8_t el_device_count = {len(program.devices)}u;",
              f"const el_chart_t el_charts[{max(1, len(program.charts))}] = {{"]
    lines += [f"    {{ {c_string(c.name)}, {len(c.steps)}u, m_c{c.id}_steps, m_c{c.id} }}," for c in program.charts] \
        or ["    { \"\", 0u, (const char *const *)0, (const uint8_t *)0 },"]
    lines += ["};", f"const uint8_t el_chart_count = {len(program.charts)}u;", ""]
    return lines + range_table(program)


def range_table(program: Program) -> list[str]:
    """The declared range of every item that has one, which the host
    board's stimulus reader holds its values to (boards/host/host_internal.h,
    el_host_ranges): the host program and every simulator harness that
    reads a stimulus compile it in."""
    rows = [f"    {{ {it.id}u, {float(it.range[0])!r}, {float(it.range[1])!r} }}, /* {it.name} */"
            for it in program.items if it.range is not None]
    return [f"const uint16_t el_host_range_count = {len(rows)}u;",
            f"const el_host_range_t el_host_ranges[{max(len(rows), 1)}] = {{"] \
        + (rows or ["    { 0u, 0.0, 0.0 },"]) + ["};", ""]


def ram_tables(program: Program, symbols: dict[str, tuple[int, int]], tick_symbol: str, where: str) -> list[str]:
    """``sim_item_addr``, ``sim_chart_addr`` and ``sim_tick_addr``: each
    item's and chart's RAM address and size in the MCU, from the linked
    program's ``symbols`` (name -> (data address, size)); ``where`` names
    the program in the error when a symbol is missing."""
    missing = []

    def address(sym: str) -> int:
        if sym not in symbols:
            missing.append(sym)
        return symbols.get(sym, (0xFFFF, 0))[0]

    lines = [f"const sim_addr_t sim_item_addr[{max(1, len(program.items))}] = {{"]
    for it in program.items:
        sym = item_symbol(program, it.id)
        lines.append(f"    {{ 0x{address(sym):04x}u, {TYPE_BYTES[it.type.name] * it.count}u }}, /* {sym} */")
    if not program.items:
        lines.append("    { 0xffffu, 0u },")
    lines += ["};", f"const sim_addr_t sim_chart_addr[{max(1, len(program.charts))}] = {{"]
    for c in program.charts:
        sym = chart_symbol(c.id)
        lines.append(f"    {{ 0x{address(sym):04x}u, {len(c.steps)}u }}, /* {sym} */")
    if not program.charts:
        lines.append("    { 0xffffu, 0u },")
    lines.append("};")
    lines.append(f"const uint16_t sim_tick_addr = 0x{address(tick_symbol):04x}u;")
    if missing:
        raise BuildError(f"{where}: symbols the simulator needs are missing: {', '.join(missing)}")
    return lines


def sim_table(c_type: str, name: str, count_name: str, rows: list[str], empty_row: str) -> list[str]:
    """A harness table and its row count: C has no empty arrays, so a table
    without rows holds ``empty_row`` (an unused row) and a count of 0."""
    return ([f"const {c_type} {name}[{max(1, len(rows))}] = {{"] + (rows or [f"    {empty_row},"])
            + ["};", f"const uint16_t {count_name} = {len(rows)}u;"])


def kept_symbols(program: Program) -> list[str]:
    """Every item and chart symbol: a simulation build keeps them all, even
    one no code reads, since the harness traces them from RAM."""
    return [item_symbol(program, it.id) for it in program.items] + [chart_symbol(c.id) for c in program.charts]


def no_model_tables(simulator: str, empty_pin: str) -> list[str]:
    """The tables of sim/sim_harness.h for a program without a
    model (a board's port contract program): one item to name, nothing to
    trace, no devices, no pins (``empty_pin``: the board's sim_pin_t
    initializer of its one unused row)."""
    return [
        f"/* Generated by EasyLab: the {simulator} harness's tables for a program without a model. */",
        "#include \"sim_model.h\"",
        "static uint16_t m_failures[1];",
        "const char el_model_name[] = \"port_program\";",
        "const uint32_t el_program_id = 0UL;",
        "const uint32_t el_tick_us = 1000UL;",
        "const uint32_t el_hyperperiod_ticks = 1UL;",
        "const el_item_t el_items[1] = { { \"failures\", m_failures, EL_T_U16, EL_K_VAR, EL_NO_DEVICE, 1u } };",
        "const uint16_t el_item_count = 1u;",
        "const el_device_t el_devices[1] = { { \"\", \"\" } };",
        "const uint8_t el_device_count = 0u;",
        "const el_chart_t el_charts[1] = { { \"\", 0u, (const char *const *)0, (const uint8_t *)0 } };",
        "const uint8_t el_chart_count = 0u;",
        "const sim_addr_t sim_item_addr[1] = { { 0xffffu, 2u } };",
        "const sim_addr_t sim_chart_addr[1] = { { 0xffffu, 0u } };",
        "const uint16_t sim_tick_addr = 0xffffu;",
        "const sim_hw_t sim_hw[1] = { { 0xffffu, SIM_HW_NONE, 0u, 0u, 0UL } };",
        "const uint16_t sim_hw_count = 0u;",
        f"const sim_pin_t sim_pins[1] = {{ {empty_pin} }};",
        "const uint16_t sim_pin_count = 0u;"]


# ====================================================================== chips

# The std chip models of sim/chips/ (docs/boards.md, "Chip models"): what
# answers on a bus where a device claims a place and its type brings no chip
# model of its own. An LM75 / TMP102-class sensor at I2C addresses
# 0x48..0x4F, a 24LC256-class EEPROM at 0x50..0x57, a 25LC256-class SPI
# EEPROM behind the chip select of std's SpiEepromLog.
STD_CHIPS = {"tmp102": "chips/tmp102.c", "eeprom_i2c": "chips/eeprom_24lc256.c",
             "eeprom_spi": "chips/eeprom_25lc256.c"}
TEMPERATURE_ADDRESSES = range(0x48, 0x50)
EEPROM_ADDRESSES = range(0x50, 0x58)
_SENSOR_TYPES = ("int8", "uint8", "int16", "uint16", "int32", "uint32")


@dataclass
class SimChip:
    """One chip of a simulation build: a row of ``sim_chip_table``
    (sim/sim_chips.h). ``values`` are (name, item id) of the device data
    whose stimulus reaches the chip, value k at index k."""

    device: Device
    file: Path          # the chip model's C file
    symbol: str         # its descriptor, EL_CHIP when it is compiled
    kind: str           # SIM_CHIP_I2C, SIM_CHIP_SPI, SIM_CHIP_UART, SIM_CHIP_PINS
    bus: int = 0
    address: int = 0
    cs: int = 0
    cs_name: str = ""
    values: list[tuple[str, int]] = field(default_factory=list)


def _place(device: Device) -> tuple[str, int, object] | None:
    """(bus kind, bus, place) of the device's first claim of a place on a bus."""
    for text in device.claims:
        claim, select = parse_claim(text), parse_select(text)
        if claim and select and claim[0] in ("i2c", "spi") and isinstance(claim[1], int):
            return claim[0], claim[1], select[1]
    return None


def _scalar_outs(program: Program, device: Device) -> list[tuple[str, int]]:
    """The device's `out` data of one value each, in declaration order, by
    the name its type gives them."""
    out = []
    for i in device.items:
        it = program.items[i]
        if it.kind == "dev_out" and it.count == 1:
            out.append((it.name[len(device.path) + 1:] if it.name.startswith(device.path + ".") else it.name, i))
    return out


def sim_chips(program: Program, board_name: str, pin_number: Callable[[str], int]) -> list[SimChip]:
    """The chips a simulator harness runs for a build on ``board_name``:
    each device's own chip model (``sim "file.c"``), at the place its claims
    give (an I2C address, a chip select numbered by ``pin_number``, a UART,
    else its pins), fed with its scalar `out` data; where a device has none,
    the std chip its place or driver calls for (STD_CHIPS)."""
    chips: list[SimChip] = []
    user_files: dict[str, str] = {}
    for dev in program.devices:
        place = _place(dev)
        if dev.chip:
            symbol = user_files.setdefault(dev.chip, f"el_chip_m{len(user_files)}")
            chip = SimChip(dev, Path(dev.chip), symbol, "SIM_CHIP_PINS", values=_scalar_outs(program, dev))
            uart = next((c for c in map(parse_claim, dev.claims) if c and c[0] == "uart"), None)
            if place and place[0] == "i2c":
                chip.kind, chip.bus, chip.address = "SIM_CHIP_I2C", place[1], int(place[2])
            elif place and place[0] == "spi":
                chip.kind, chip.bus, chip.cs, chip.cs_name = "SIM_CHIP_SPI", place[1], pin_number(place[2]), place[2]
            elif uart is not None and isinstance(uart[1], int):
                chip.kind, chip.bus = "SIM_CHIP_UART", uart[1]
            chips.append(chip)
            continue
        std = sim_dir()
        if place and place[0] == "i2c" and place[2] in TEMPERATURE_ADDRESSES:
            sensor = next(((n, i) for n, i in _scalar_outs(program, dev)
                           if program.items[i].type.name in _SENSOR_TYPES), None)
            chips.append(SimChip(dev, std / STD_CHIPS["tmp102"], "el_chip_std_tmp102", "SIM_CHIP_I2C", place[1],
                                 place[2], values=[sensor] if sensor else []))
        elif place and place[0] == "i2c" and place[2] in EEPROM_ADDRESSES:
            chips.append(SimChip(dev, std / STD_CHIPS["eeprom_i2c"], "el_chip_std_eeprom_i2c", "SIM_CHIP_I2C",
                                 place[1], place[2]))
        elif place and place[0] == "spi" and dev.driver == "spi_eeprom_log" and board_name not in dev.handlers:
            chips.append(SimChip(dev, std / STD_CHIPS["eeprom_spi"], "el_chip_std_eeprom_spi", "SIM_CHIP_SPI",
                                 place[1], cs=pin_number(place[2]), cs_name=place[2]))
    return chips


def chip_sources(chips: list[SimChip]) -> list[tuple[Path, str]]:
    """Each chip model file once, with its descriptor's name: a harness
    compiles it with ``-DEL_CHIP=<name>``."""
    return list(dict.fromkeys((c.file, c.symbol) for c in chips))


def chip_value_rows(chips: list[SimChip]) -> dict[int, tuple[int, int]]:
    """item id -> (chip index, value k): the ``SIM_HW_CHIP`` rows of
    ``sim_hw`` (the stimulus of a device datum goes to its chip)."""
    return {item: (n, k) for n, c in enumerate(chips) for k, (_name, item) in enumerate(c.values)}


def chip_tables(chips: list[SimChip]) -> list[str]:
    """``sim_chip_table`` and what its rows point to: the chip models'
    descriptors, value names, and the devices' integer parameters (which a
    chip reads with el_chip_param)."""
    lines = [f"extern const el_chip_ops_t {symbol};" for _file, symbol in chip_sources(chips)]
    rows = []
    for n, c in enumerate(chips):
        names = [c_string(name) for name, _item in c.values]
        params = [(k, v) for k, (t, v) in c.device.params.items()
                  if isinstance(v, (bool, int)) and t.name != "float32"]
        lines.append(f"static const char *const chip{n}_values[{max(1, len(names))}] = "
                     f"{{ {', '.join(names) or '0'} }};")
        lines.append(f"static const char *const chip{n}_param_names[{max(1, len(params))}] = "
                     f"{{ {', '.join(c_string(k) for k, _v in params) or '0'} }};")
        lines.append(f"static const int64_t chip{n}_param_values[{max(1, len(params))}] = "
                     f"{{ {', '.join(f'{int(v)}LL' for _k, v in params) or '0'} }};")
        rows.append(f"    {{ &{c.symbol}, {c.kind}, {c.bus}u, 0x{c.address:02x}u, 0x{c.cs:04x}u, {c_string(c.cs_name)}, "
                    f"{c_string(c.device.path)}, {len(names)}u, chip{n}_values, {len(params)}u, chip{n}_param_names, "
                    f"chip{n}_param_values }},")
    return lines + sim_table("sim_chip_entry_t", "sim_chip_table", "sim_chip_table_count", rows,
                             "{ 0, 0u, 0u, 0u, 0u, \"\", \"\", 0u, 0, 0u, 0, 0 }")
