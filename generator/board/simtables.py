"""The tables a simulator harness compiles in to trace a firmware: the
model's items and charts as the host board's trace code sees them
(runtime_c/el_model.h, over host-side mirrors), and where each lives in
the simulated MCU's RAM. A harness reads the values straight from the
MCU's memory at each instant and writes them with the host board's own
trace code, so its trace files equal the host board's byte for byte.

The chips a harness runs on its buses are generic too (sim/sim_chips.h):
``sim_chip_table`` with a model's own chip models and, for a harness that
runs them, the std ones (:func:`sim_chips`), and the ``SIM_HW_CHIP`` rows
that take a device datum's stimulus to its chip.

The address tables use the types of a harness's ``sim_model.h``::

    typedef struct { uint16_t addr; uint16_t size; } sim_addr_t;
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ..codegen.c_syntax import C_KIND_ENUM, C_TYPE_ENUM, c_string, ident
from ..codegen.device_state import packed_fields, state_devices, state_symbol
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


def state_tables(program: Program, board: str, symbols: dict[str, tuple[int, int]], where: str) -> list[str]:
    """``el_host_state_items`` over host-side mirrors ``m_s<k>`` (the
    `state` fields of the devices running ``board``'s handler files, named
    ``DEVICE.FIELD`` in device then field order, as the host board's trace
    has them: host_internal.h) and ``sim_state_addr``, each field's RAM
    address in the MCU: its device's ``el_mdev<id>_state`` from the linked
    program's ``symbols`` plus the field's offset in the layout the firmware
    checks (device_state.layout_check_lines); ``where`` names the program
    in the error when a state is missing."""
    mirrors, rows, addresses, missing = [], [], [], []
    for dev in state_devices(program, board):
        base = symbols.get(state_symbol(dev))
        if base is None:
            missing.append(state_symbol(dev))
        for name, t, count, offset in packed_fields(dev):
            k = len(rows)
            mirrors.append(f"static {t.c_name} m_s{k}[{count}];")
            rows.append(f"    {{ {c_string(f'{dev.path}.{name}')}, m_s{k}, {C_TYPE_ENUM[t.name]}, EL_K_DEV_STATE, "
                        f"{dev.id}u, {count}u }},")
            addr = 0xFFFF if base is None else base[0] + offset
            addresses.append(f"    {{ 0x{addr:04x}u, {t.bits // 8 * count}u }}, /* {state_symbol(dev)}.{name} */")
    if missing:
        raise BuildError(f"{where}: symbols the simulator needs are missing: {', '.join(missing)}")
    return mirrors + sim_table("el_item_t", "el_host_state_items", "el_host_state_item_count", rows,
                               '{ "", (void *)0, 0u, 0u, EL_NO_DEVICE, 0u }') \
        + sim_table("sim_addr_t", "sim_state_addr", "sim_state_addr_count", addresses, "{ 0xffffu, 0u }")


def sim_table(c_type: str, name: str, count_name: str, rows: list[str], empty_row: str) -> list[str]:
    """A harness table and its row count: C has no empty arrays, so a table
    without rows holds ``empty_row`` (an unused row) and a count of 0."""
    return ([f"const {c_type} {name}[{max(1, len(rows))}] = {{"] + (rows or [f"    {empty_row},"])
            + ["};", f"const uint16_t {count_name} = {len(rows)}u;"])


def kept_symbols(program: Program, board: str | None = None) -> list[str]:
    """Every item and chart symbol, and with ``board`` every device state
    there: a simulation build keeps them all, even one no code reads, since
    the harness traces them from RAM."""
    states = [state_symbol(d) for d in state_devices(program, board)] if board is not None else []
    return [item_symbol(program, it.id) for it in program.items] + [chart_symbol(c.id) for c in program.charts] \
        + states


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
        "const el_item_t el_host_state_items[1] = { { \"\", (void *)0, 0u, 0u, EL_NO_DEVICE, 0u } };",
        "const uint16_t el_host_state_item_count = 0u;",
        "const sim_addr_t sim_state_addr[1] = { { 0xffffu, 0u } };",
        "const uint16_t sim_state_addr_count = 0u;",
        "const sim_hw_t sim_hw[1] = { { 0xffffu, SIM_HW_NONE, 0u, 0u, 0UL } };",
        "const uint16_t sim_hw_count = 0u;",
        f"const sim_pin_t sim_pins[1] = {{ {empty_pin} }};",
        "const uint16_t sim_pin_count = 0u;"]


# ---------------------------------------------------------------- chip models

# The std chip models of sim/chips/ (docs/boards.md, "Chip models"): what a
# harness that runs them (``std_for``: the board's name) puts where a device
# claims a place on a bus and its type brings no chip model of its own: an
# LM75 / TMP102-class sensor at I2C addresses 0x48..0x4F, a 24LC256-class
# EEPROM at 0x50..0x57, a 25LC256-class SPI EEPROM behind the chip select of
# a std SpiEepromLog the board drives itself.
STD_CHIPS = {"el_chip_std_tmp102": "chips/tmp102.c", "el_chip_std_24lc256": "chips/eeprom_24lc256.c",
             "el_chip_std_25lc256": "chips/eeprom_25lc256.c"}
TEMPERATURE_ADDRESSES = range(0x48, 0x50)
EEPROM_ADDRESSES = range(0x50, 0x58)
_SENSOR_TYPES = ("int8", "uint8", "int16", "uint16", "int32", "uint32")


@dataclass
class SimChip:
    """A row of sim_chip_table (sim/sim_chips.h): the device, its chip
    model's file and descriptor, its place, and the items whose stimulus
    reaches it (value k is ``values[k]``)."""

    device: Device
    file: str
    symbol: str
    kind: str = "0"
    bus: int = 0
    address: int = 0
    cs_name: str = ""
    values: list[int] = field(default_factory=list)
    pins: list[str] = field(default_factory=list)


def _place(chip: SimChip) -> SimChip:
    """The chip at the place its device claims: an I2C address, a chip
    select, else a UART, else its pins alone; with the pins it claims (in
    claim order: what it sees and drives, el_chip.h) whatever its place."""
    for text in chip.device.claims:
        claim, select = parse_claim(text), parse_select(text)
        if claim and claim[0] == "i2c" and select and select[0] == "addr":
            chip.kind, chip.bus, chip.address = "SIM_CHIP_I2C", int(claim[1]), int(select[1])
        elif claim and claim[0] == "spi" and select and select[0] == "cs":
            chip.kind, chip.bus, chip.cs_name = "SIM_CHIP_SPI", int(claim[1]), str(select[1])
        elif claim and claim[0] == "uart" and chip.kind == "0":
            chip.kind, chip.bus = "SIM_CHIP_UART", int(claim[1])
        elif claim and claim[0] == "pin":
            chip.pins.append(str(claim[1]))
    if chip.kind == "0" and chip.pins:
        chip.kind = "SIM_CHIP_PINS"
    return chip


def sim_chips(program: Program | None, std_for: str | None = None) -> list[SimChip]:
    """The chips of a simulation build, in device order: every device whose
    type brings a chip model (`sim "FILE.c"`: the symbol el_chip_<k>, fed
    with all its `out` data), and with ``std_for`` (the board's name) the std
    chip a device without one calls for (STD_CHIPS; a sensor fed with its
    first integer `out` datum)."""
    chips: list[SimChip] = []
    for dev in [] if program is None else program.devices:
        if dev.chip:
            outs = [i for i in dev.items if program.items[i].kind == "dev_out"]
            chips.append(_place(SimChip(dev, dev.chip, chip_symbol(len(chips)), values=outs)))
            continue
        if std_for is None:
            continue
        chip = _place(SimChip(dev, "", ""))
        if chip.kind == "SIM_CHIP_I2C" and chip.address in TEMPERATURE_ADDRESSES:
            chip.symbol = "el_chip_std_tmp102"
            chip.values = [i for i in dev.items if program.items[i].kind == "dev_out"
                           and program.items[i].type.name in _SENSOR_TYPES and program.items[i].count == 1][:1]
        elif chip.kind == "SIM_CHIP_I2C" and chip.address in EEPROM_ADDRESSES:
            chip.symbol = "el_chip_std_24lc256"
        elif chip.kind == "SIM_CHIP_SPI" and dev.driver == "spi_eeprom_log" and std_for not in dev.handlers:
            chip.symbol = "el_chip_std_25lc256"
        else:
            continue
        chip.file = str(sim_dir() / STD_CHIPS[chip.symbol])
        chips.append(chip)
    return chips


def chip_devices(program: Program | None, std_for: str | None = None) -> list:
    """The devices of sim_chip_table, in its order (:func:`sim_chips`)."""
    return [c.device for c in sim_chips(program, std_for)]


def chip_symbol(index: int) -> str:
    """The descriptor a chip file defines under the name EL_CHIP (sim/el_chip.h)."""
    return f"el_chip_{index}"


def chip_files(program: Program | None, std_for: str | None = None) -> list[tuple[str, str]]:
    """(chip model file, its EL_CHIP symbol) to compile into the harness,
    each with -DEL_CHIP=symbol: a model's chip file once per device, a std
    chip once whatever the devices using it."""
    return list(dict.fromkeys((c.file, c.symbol) for c in sim_chips(program, std_for)))


def chip_table(program: Program | None, pin_number, std_for: str | None = None) -> list[str]:
    """sim_chip_table (sim/sim_chips.h): one entry per chip of
    :func:`sim_chips`, at the I2C address, chip select or UART it claims,
    with the pins it claims (``pin_number(name)``: the harness's number of
    a pin), the names of the data whose stimulus reaches it and its
    device's integer parameters (el_chip_param)."""
    lines, rows = [], []
    chips = sim_chips(program, std_for)
    for symbol in dict.fromkeys(c.symbol for c in chips):
        lines.append(f"extern const el_chip_ops_t {symbol};")
    for k, c in enumerate(chips):
        names = ", ".join(c_string(program.items[i].name.rsplit(".", 1)[-1]) for i in c.values) or "\"\""
        params = [(name, v) for name, (t, v) in c.device.params.items()
                  if isinstance(v, (bool, int)) and t.name != "float32"]
        lines.append(f"static const char *const sim_chip_values_{k}[] = {{ {names} }};")
        lines.append(f"static const char *const sim_chip_param_names_{k}[] = "
                     f"{{ {', '.join(c_string(n) for n, _v in params) or '0'} }};")
        lines.append(f"static const int64_t sim_chip_param_values_{k}[] = "
                     f"{{ {', '.join(f'{int(v)}LL' for _n, v in params) or '0'} }};")
        pins = ", ".join(f"{pin_number(p)}u /* {p} */" for p in c.pins) or "0u"
        lines.append(f"static const uint16_t sim_chip_pins_{k}[] = {{ {pins} }};")
        cs = pin_number(c.cs_name) if c.cs_name else 0
        rows.append(f"    {{ &{c.symbol}, {c.kind}, {c.bus}u, 0x{c.address:02x}u, {cs}u, {c_string(c.cs_name)}, "
                    f"{c_string(c.device.path)}, {len(c.values)}u, sim_chip_values_{k}, {len(params)}u, "
                    f"sim_chip_param_names_{k}, sim_chip_param_values_{k}, {len(c.pins)}u, sim_chip_pins_{k} }},")
    if not rows:
        return ["#include \"sim_chips.h\"",
                "const sim_chip_entry_t sim_chip_table[1] = "
                "{ { 0, 0u, 0u, 0u, 0u, \"\", \"\", 0u, 0, 0u, 0, 0, 0u, 0 } };",
                "const uint16_t sim_chip_table_count = 0u;"]
    return ["#include \"sim_chips.h\"", *lines,
            f"const sim_chip_entry_t sim_chip_table[{len(rows)}] = {{", *rows, "};",
            f"const uint16_t sim_chip_table_count = {len(rows)}u;"]


def chip_hardware_row(program: Program, item, std_for: str | None = None) -> str | None:
    """The sim_hw row of a device `out` datum whose value the stimulus gives
    a chip (SIM_HW_CHIP: a the chip, b the value), else None."""
    for k, c in enumerate(sim_chips(program, std_for)):
        if item.id in c.values:
            what = "its chip model" if c.device.chip else f"the std chip {c.symbol[len('el_chip_std_'):]}"
            return (f"    {{ {item.id}u, SIM_HW_CHIP, {k}u, {c.values.index(item.id)}u, 0UL }}, "
                    f"/* {item.name} ({what}) */")
    return None
