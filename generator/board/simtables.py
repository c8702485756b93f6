"""The tables a simulator harness compiles in to trace a firmware: the
model's items and charts as the host board's trace code sees them
(runtime_c/el_model.h, over host-side mirrors), and where each lives in
the simulated MCU's RAM. A harness reads the values straight from the
MCU's memory at each instant and writes them with the host board's own
trace code, so its trace files equal the host board's byte for byte.

The address tables use the types of a harness's ``sim_model.h``::

    typedef struct { uint16_t addr; uint16_t size; } sim_addr_t;
"""

from __future__ import annotations

from ..codegen.c_syntax import C_KIND_ENUM, C_TYPE_ENUM, c_string, ident
from ..core.errors import BuildError
from ..ir.program import Program

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


# ---------------------------------------------------------------- chip models


def chip_devices(program: Program | None) -> list:
    """The devices whose types bring a chip model (`sim "FILE.c"`), in
    device order: index k is sim_chip_table[k] and the symbol el_chip_<k>
    (none for a program without a model)."""
    return [] if program is None else [dev for dev in program.devices if dev.chip]


def chip_symbol(index: int) -> str:
    """The descriptor a chip file defines under the name EL_CHIP (sim/el_chip.h)."""
    return f"el_chip_{index}"


def chip_files(program: Program | None) -> list[tuple[str, str]]:
    """(chip model file, its EL_CHIP symbol) of every chip device: the
    harness compiles each file once per device, with -DEL_CHIP=symbol."""
    return [(dev.chip, chip_symbol(k)) for k, dev in enumerate(chip_devices(program))]


def chip_table(program: Program | None, pin_number) -> list[str]:
    """sim_chip_table (sim/sim_chips.h): one entry per chip device, at the
    I2C address or chip select it claims (``pin_number(name)``: the
    harness's number of a pin), with the names of its `out` data (the
    stimulus columns whose values reach the chip)."""
    from .claims import parse_claim, parse_select

    lines, rows = [], []
    for k, dev in enumerate(chip_devices(program)):
        kind, bus, address, cs, cs_name = "0", 0, 0, 0, ""
        for text in dev.claims:
            claim, select = parse_claim(text), parse_select(text)
            if claim and claim[0] == "i2c" and select and select[0] == "addr":
                kind, bus, address = "SIM_CHIP_I2C", int(claim[1]), int(select[1])
            elif claim and claim[0] == "spi" and select and select[0] == "cs":
                kind, bus, cs_name = "SIM_CHIP_SPI", int(claim[1]), str(select[1])
                cs = pin_number(cs_name)
            elif claim and claim[0] == "uart":
                kind, bus = "SIM_CHIP_UART", int(claim[1])
        outs = [program.items[i] for i in dev.items if program.items[i].kind == "dev_out"]
        names = ", ".join(c_string(it.name.rsplit(".", 1)[-1]) for it in outs) or "\"\""
        lines.append(f"extern const el_chip_ops_t {chip_symbol(k)};")
        lines.append(f"static const char *const sim_chip_values_{k}[] = {{ {names} }};")
        rows.append(f"    {{ &{chip_symbol(k)}, {kind}, {bus}u, 0x{address:02x}u, {cs}u, {c_string(cs_name)}, "
                    f"{c_string(dev.path)}, {len(outs)}u, sim_chip_values_{k} }},")
    if not rows:
        return ["#include \"sim_chips.h\"",
                "const sim_chip_entry_t sim_chip_table[1] = { { 0, 0u, 0u, 0u, 0u, \"\", \"\", 0u, 0 } };",
                "const uint16_t sim_chip_table_count = 0u;"]
    return ["#include \"sim_chips.h\"", *lines,
            f"const sim_chip_entry_t sim_chip_table[{len(rows)}] = {{", *rows, "};",
            f"const uint16_t sim_chip_table_count = {len(rows)}u;"]


def chip_hardware_row(program: Program, item) -> str | None:
    """The sim_hw row of a device `out` datum whose value the stimulus gives
    the device's chip model (SIM_HW_CHIP: a the chip, b the value), else None."""
    devices = chip_devices(program)
    dev = program.devices[item.device]
    if not dev.chip or item.kind != "dev_out":
        return None
    outs = [i for i in dev.items if program.items[i].kind == "dev_out"]
    return (f"    {{ {item.id}u, SIM_HW_CHIP, {devices.index(dev)}u, {outs.index(item.id)}u, 0UL }}, "
            f"/* {item.name} (its chip model) */")
