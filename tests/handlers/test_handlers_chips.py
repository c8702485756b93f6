"""Chip models a model brings (`sim "file.c"` after a device type's driver;
docs/boards.md, "Chip models"): the checker's rules, and devices of the
model's own run for real, the AVR firmware in simavr against their chip
models, the host board and local execution, which must give one trace;
what a chip select or an I2C address nobody answers gives the handlers."""

from __future__ import annotations

import re
import shutil
from pathlib import Path
from textwrap import dedent

import pytest

from easylab.pipeline import lower_file

from firmware_builds import ROOT
from handlers_testlib import build, interpret, run, trace_rows, write_model
from test_handlers_model import diagnostics

OWN = ROOT / "examples" / "own_chips"


@pytest.fixture(scope="module")
def own(tmp_path_factory):
    """examples/own_chips/ copied to a folder of its own outside the
    installation, built for the AVR (ATmega328P, --sim) and the host."""
    folder = tmp_path_factory.mktemp("own") / "own_chips"
    shutil.copytree(OWN, folder)
    model = folder / "own_chips.elab"
    return model, build(model, "avr", folder / "avr", "--sim"), build(model, "host", folder / "host")


def test_an_spi_adc_and_an_i2c_sensor_of_the_models_own_run_alike_in_simavr_on_the_host_and_locally(own, tmp_path):
    model, avr, host = own
    args = ["--fast", "--duration", "80ms", "--stimulus", model.with_name("own_chips.stimulus.csv")]
    run(avr.simulator, *args, "--trace", tmp_path / "avr.csv")
    run(host.executable, *args, "--trace", tmp_path / "host.csv")
    interpret(model, *args, "--trace", tmp_path / "local.csv", cache=tmp_path / "cache")
    host_trace = (tmp_path / "host.csv").read_bytes()
    assert (tmp_path / "avr.csv").read_bytes() == host_trace
    assert (tmp_path / "local.csv").read_bytes() == host_trace
    _, rows = trace_rows(tmp_path / "avr.csv")
    by_time = {int(r["time_us"]): r for r in rows}
    # The ADC's 12 bits and the sensor's count converted to 0.1 %RH came
    # through the firmware's own drivers from the chip models.
    assert [by_time[t]["adc.value"] for t in (0, 20000, 40000, 60000)] == ["0", "4095", "1234", "2049"]
    assert [by_time[t]["hum.humidity"] for t in (0, 20000, 40000, 60000)] == ["0", "1000", "500", "15"]
    assert by_time[70000]["level"] == "2049"


def test_the_docs_show_the_example_the_tests_build_and_run():
    """docs/boards.md's SPI device (model, handlers, chip model) is
    examples/own_chips/ as the test above builds and runs it, word for
    word; docs/language.md's device type is the model's."""
    doc = (ROOT / "docs" / "boards.md").read_text()
    shown = dict(re.findall(r"`(examples/own_chips/[^`]+)`:\n\n```\w*\n(.*?)```\n", doc, re.S))
    assert sorted(shown) == ["examples/own_chips/drivers/mcp3201_avr.c", "examples/own_chips/drivers/mcp3201_chip.c",
                             "examples/own_chips/drivers/mcp3201_host.c", "examples/own_chips/own_chips.elab"]
    for rel, text in shown.items():
        assert text == (ROOT / rel).read_text(), rel
    language = (ROOT / "docs" / "language.md").read_text()
    [device_type] = re.findall(r"```\n(device type Mcp3201.*?)```\n", language, re.S)
    assert device_type in (OWN / "own_chips.elab").read_text()


def test_a_chip_model_refuses_a_value_it_cannot_have(own, tmp_path):
    _model, avr, _host = own
    stim = tmp_path / "s.csv"
    stim.write_text("time_us,adc.value\n0,100\n20000,4096\n")
    proc = run(avr.simulator, "--fast", "--duration", "50ms", "--stimulus", stim, "--trace", tmp_path / "t.csv",
               ok=False)
    assert proc.returncode == 1
    assert "device 'adc': value = 4096: a 12-bit ADC converts 0 .. 4095" in proc.stderr
    assert "adc.value: the stimulus at 20000 us gives the chip model a value it refuses" in proc.stderr


def test_the_ir_carries_the_chip_model_and_it_changes_nothing_of_the_firmware(tmp_path):
    folder = tmp_path / "m"
    shutil.copytree(OWN, folder)
    program, result = lower_file(folder / "own_chips.elab")
    assert program is not None, result.report()
    chips = {d.path: d.chip for d in program.devices}
    assert chips == {"adc": str(folder / "drivers" / "mcp3201_chip.c"), "hum": str(folder / "drivers" / "hum16_chip.c")}
    text = (folder / "own_chips.elab").read_text()
    # The same lines (locations are part of the IR), without the chip models.
    (folder / "own_chips.elab").write_text(text.replace('sim "drivers/mcp3201_chip.c"', "")
                                           .replace(' sim "drivers/hum16_chip.c"', ""))
    without, _ = lower_file(folder / "own_chips.elab")
    assert [d.chip for d in without.devices] == [None, None]
    assert without.program_id == program.program_id


CHIP_TYPE = dedent("""\
    model m
    import std
    device type Adc(cs: string) {
        claims spi[0] cs cs
        out value: uint16
        driver "adc" impl avr "adc_avr.c" sim "chips/adc_chip.c"
    }
    device a: Adc(cs = "PB2")
    var v: uint16
    dataflow D { a.value -> v }
    task t period 10 ms { run D }
    """)


def test_a_chip_model_that_is_not_there_is_an_error_at_its_sim(tmp_path):
    path = write_model(tmp_path, CHIP_TYPE, {"adc_avr.c": ""})
    assert diagnostics(path) == [
        (6, 39, f"chip model 'chips/adc_chip.c' not found (looked at {tmp_path / 'chips/adc_chip.c'})", None)]


def test_a_type_has_one_chip_model(tmp_path):
    text = CHIP_TYPE.replace('sim "chips/adc_chip.c"', 'sim "chips/adc_chip.c" sim "chips/adc_chip.c"')
    path = write_model(tmp_path, text, {"adc_avr.c": "", "chips/adc_chip.c": ""})
    [(line, col, message, _hint)] = diagnostics(path)
    assert (line, col, message) == (6, 62, "device type 'Adc' has two chip models: a type has at most one 'sim' file")


def test_a_chip_model_that_does_not_compile_fails_the_simulation_build_naming_its_line(tmp_path):
    chip = "#include \"el_chip.h\"\nconst el_chip_ops_t EL_CHIP = { .name = \"adc\" };\nint broken(void) { return x; }\n"
    path = write_model(tmp_path, CHIP_TYPE, {"adc_avr.c": "", "chips/adc_chip.c": chip})
    built = build(path, "avr", tmp_path / "out", "--sim", ok=False)
    out = built.proc.stdout + built.proc.stderr
    assert "building the chip model" in out
    assert re.search(r"chips/adc_chip\.c:3:\d+: error: .x. undeclared", out), out


# ---- chips nobody models: one behaviour, whatever else the model has ----

PROBES = dedent("""\
    model probes
    import std
    // Handlers that report what the bus gave them (runtime_c/el_bus.h).
    device type SpiProbe(cs: string) {
        claims spi[0] cs cs
        out first: uint8
        out second: uint8
        driver "spi_probe" impl avr "probes.c"
    }
    device type I2cProbe(address: uint8) {
        claims i2c[0] addr address
        out status: uint8
        driver "i2c_probe" impl avr "i2c_probe.c"
    }
    device nobody_spi: SpiProbe(cs = "PD7")
    device nobody_i2c: I2cProbe(address = 0x21)
    var first: uint8
    var second: uint8
    var status: uint8
    dataflow D { nobody_spi.first -> first  nobody_spi.second -> second  nobody_i2c.status -> status }
    task t period 10 ms { run D }
    """)
PROBES_C = {
    "probes.c": dedent("""\
        EL_OPEN {
            (void)el_spi_open(0u, EL_CS);
        }
        EL_READ {
            uint8_t io[2] = {0x12u, 0x34u};
            (void)el_spi_transfer(0u, EL_CS, EL_SPI_MODE0, io, io, 2u);
            first = io[0];
            second = io[1];
        }
        """),
    "i2c_probe.c": dedent("""\
        EL_READ {
            static const uint8_t pointer = 0u;
            uint8_t reg[2];
            status = el_i2c_transfer(0u, address, &pointer, 1u, reg, 2u);
        }
        """),
}
# The own_chips example's two devices (and its files), and std's chips.
OTHERS = dedent("""\
    device type Mcp3201(bus: uint8 = 0, cs: string) {
        claims spi[bus] cs cs
        out value: uint16
        driver "mcp3201" impl avr "drivers/mcp3201_avr.c" sim "drivers/mcp3201_chip.c"
    }
    device type Hum16(bus: uint8 = 0, address: uint8 = 0x40) {
        claims i2c[bus] addr address
        out humidity: uint16
        state failures: uint16
        driver "hum16" impl avr "drivers/hum16_avr.c" sim "drivers/hum16_chip.c"
    }
    device adc: Mcp3201(cs = "PB2")
    device hum: Hum16()
    device room: I2cTemperature()
    device log: SpiEepromLog(cs = "PB1", values = 1)
    var level: uint16
    dataflow E { adc.value -> level  room.temperature -> log.record }
    task u period 10 ms { run E }
    """)


@pytest.mark.parametrize("others", [False, True], ids=["alone", "among-chips"])
def test_a_chip_select_nobody_answers_reads_0xff_and_an_address_nobody_acknowledges_is_a_nack(tmp_path, others):
    files = dict(PROBES_C)
    text = PROBES
    if others:
        text += OTHERS
        files.update({f"drivers/{p.name}": p.read_text() for p in (OWN / "drivers").iterdir()})
    path = write_model(tmp_path, text, files)
    avr = build(path, "avr", tmp_path / "avr", "--sim")
    stim = tmp_path / "s.csv"
    stim.write_text("time_us,adc.value\n0,3000\n" if others else "time_us\n0\n")
    run(avr.simulator, "--fast", "--duration", "30ms", "--stimulus", stim, "--trace", tmp_path / "avr.csv")
    _, rows = trace_rows(tmp_path / "avr.csv")
    last = rows[-1]
    assert (last["first"], last["second"]) == ("255", "255")  # the idle MISO, pulled up
    assert last["status"] == "2"  # EL_BUS_NACK
    if others:
        assert last["level"] == "3000"  # the ADC's chip model on the same bus
        assert last["room.temperature"] == "0"
