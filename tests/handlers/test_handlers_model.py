"""Device handlers and bus claims in the language (docs/language.md, §4
"Device handlers" and "Resources"): what the checker accepts, what it
refuses (each error at its line and column), and what the IR carries."""

from __future__ import annotations

from pathlib import Path
from textwrap import dedent

import pytest

from easylab.core import types as T
from easylab.pipeline import check_file, lower_file

from handlers_testlib import write_model

SENSOR = dedent("""\
    model m
    import std
    device type Tmp102(bus: uint8 = 0, address: uint8 = 0x48, label: string = "room") {
        claims i2c[bus] addr address
        out temperature: int16
        out history: int16 rate 2
        state reads: uint16
        state window: int16[4]
        driver "tmp102" impl avr "drivers/tmp102_avr.c" impl host "drivers/tmp102_sim.c"
    }
    device probe: Tmp102(address = 0x49)
    var t: int16
    var h: int16
    dataflow D {
        d = Downsample<int16>(factor = 2)
        probe.temperature -> t
        probe.history -> d.x
        d.y -> h
    }
    task a period 10 ms { run D }
    """)
FILES = {"drivers/tmp102_avr.c": "EL_READ { temperature = 1; }\n", "drivers/tmp102_sim.c": "EL_READ { }\n"}


def diagnostics(path: Path) -> list[tuple[int, int, str, str | None]]:
    result = check_file(path)
    assert result.model is None
    return [(d.span.line, d.span.column, d.message, d.hint) for d in result.diagnostics.sorted()]


def test_a_device_type_brings_its_handlers_per_board_and_the_ir_carries_them(tmp_path):
    path = write_model(tmp_path, SENSOR, FILES)
    program, result = lower_file(path)
    assert program is not None, result.report()
    [dev] = program.devices
    assert dev.handlers == {"avr": str(tmp_path / "drivers/tmp102_avr.c"),
                            "host": str(tmp_path / "drivers/tmp102_sim.c")}
    assert dev.driver == "tmp102" and dev.claims == ["i2c[0] addr 0x49"]
    assert dev.params == {"bus": (T.UINT8, 0), "address": (T.UINT8, 0x49), "label": (T.STRING, "room")}
    assert dev.states == [("reads", T.UINT16, None), ("window", T.INT16, 4)]
    assert dev.array_ports == ["history"]


def test_a_handler_file_that_is_not_there_is_an_error_at_its_impl(tmp_path):
    path = write_model(tmp_path, SENSOR, {"drivers/tmp102_avr.c": ""})
    [(line, col, message, _hint)] = diagnostics(path)
    assert (line, col) == (9, 53)
    assert message == (f"handler file 'drivers/tmp102_sim.c' not found (looked at "
                       f"{tmp_path / 'drivers/tmp102_sim.c'})")


def test_two_handler_files_for_one_board_are_an_error(tmp_path):
    text = SENSOR.replace('impl host "drivers/tmp102_sim.c"', 'impl avr "drivers/tmp102_sim.c"')
    path = write_model(tmp_path, text, FILES)
    assert diagnostics(path) == [(9, 58, "device type 'Tmp102' has two handler files for board 'avr'", None)]


def test_state_needs_handler_files(tmp_path):
    text = SENSOR.replace(' impl avr "drivers/tmp102_avr.c" impl host "drivers/tmp102_sim.c"', "")
    path = write_model(tmp_path, text, FILES)
    assert diagnostics(path) == [
        (7, 5, "device type 'Tmp102' has state but no handler files: state is kept for the handlers a model "
               "brings", 'name them after the driver: driver "name" impl BOARD "file.c"')]


@pytest.mark.parametrize("old, new, line, col, what", [
    ("state reads: uint16", "state el_reads: uint16", 7, 11, "state 'el_reads'"),
    ("label: string", "float: string", 3, 59, "parameter 'float'"),
    ("out temperature", "out int32_t", 5, 9, "port 'int32_t'"),
])
def test_names_the_handlers_c_cannot_see_are_refused(tmp_path, old, new, line, col, what):
    path = write_model(tmp_path, SENSOR.replace(old, new), FILES)
    [(l, c, message, hint)] = [d for d in diagnostics(path) if "cannot be named" in d[2]]
    assert (l, c) == (line, col)
    assert message == f"{what} of device type 'Tmp102' cannot be named like that: its handlers' C code sees it " \
                      "under its own name"
    assert hint == "C keywords, C type names and names starting with el_ are reserved"


def test_a_second_device_at_one_i2c_address_is_refused_naming_both(tmp_path):
    path = write_model(tmp_path, SENSOR.replace("device probe: Tmp102(address = 0x49)",
                                                "device probe: Tmp102(address = 0x49)\n"
                                                "device other: Tmp102(address = 0x49)"), FILES)
    result = check_file(path)
    [d] = result.diagnostics.sorted()
    assert (d.span.line, d.span.column) == (12, 1)
    assert d.message == ("i2c[0] addr 0x49 is claimed by device 'other' and by device 'probe': the devices on one "
                         "bus need distinct places on it")
    assert d.hint == "give one of them another address"
    assert [(n.span.line, n.message) for n in d.notes] == [(11, "claimed by device 'probe' here")]


def test_devices_at_distinct_addresses_share_the_bus(tmp_path):
    path = write_model(tmp_path, SENSOR.replace("device probe: Tmp102(address = 0x49)",
                                                "device probe: Tmp102(address = 0x49)\n"
                                                "device other: Tmp102(address = 0x4a)"), FILES)
    result = check_file(path)
    assert result.model is not None, result.report()


def test_a_bus_owned_whole_is_shared_with_nobody(tmp_path):
    text = SENSOR + dedent("""\
        device type BusMaster() {
            claims i2c0
            out level: bool
            driver "bus_master"
        }
        device master: BusMaster()
        var m: bool
        dataflow E { master.level -> m }
        task b period 10 ms { run E }
        """)
    path = write_model(tmp_path, text, FILES)
    result = check_file(path)
    [d] = result.diagnostics.sorted()
    assert (d.span.line, d.message) == (26, "resource i2c[0] is claimed by device 'master' and by device 'probe' "
                                            "(i2c[0] addr 0x49)")


@pytest.mark.parametrize("claim, message", [
    ('i2c[0] addr "x"', "a bus address is a non-negative integer, as in addr 0x48"),
    ('spi[0] cs 2 > 1', 'a chip select is a pin: its name as a string, as in cs "PB2"'),
    ('spi[0] cs 2', 'a chip select is a pin: its name as a string, as in cs "PB2"'),  # once a build error
])
def test_a_place_on_a_bus_has_a_type(tmp_path, claim, message):
    path = write_model(tmp_path, SENSOR.replace("claims i2c[bus] addr address", f"claims {claim}"), FILES)
    assert [d[2] for d in diagnostics(path)] == [message]


def test_addr_and_cs_stay_names_and_kindn_works_for_buses(tmp_path):
    text = SENSOR.replace("address: uint8 = 0x48", "addr: uint8 = 0x48").replace("i2c[bus] addr address",
                                                                                 "i2c0 addr addr") \
        .replace("Tmp102(address = 0x49)", "Tmp102(addr = 0x49)")
    program, result = lower_file(write_model(tmp_path, text, FILES))
    assert program is not None, result.report()
    assert program.devices[0].claims == ["i2c[0] addr 0x49"]
