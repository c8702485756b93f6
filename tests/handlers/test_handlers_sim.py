"""Devices with handlers from the model's folder and devices on the I2C bus,
run for real: the AVR firmware in simavr against the harness's chip models
(a TMP102-class sensor, a 24LC256-class EEPROM), the host board and local
execution, which must give the same trace; what reaches the EEPROM; what
the bus does when a chip is missing, busy or too slow."""

from __future__ import annotations

import shutil
from pathlib import Path
from textwrap import dedent

import pytest

from firmware_builds import ROOT
from handlers_testlib import (LOGGER, LOGGER_STIMULUS, build, eeprom_log, interpret, run, trace_rows,
                              write_model)


@pytest.fixture(scope="module")
def logger(build_cache):
    """The PT100 logger example built for the AVR (ATmega328P, --sim) and the host."""
    avr = build_cache.get(("handlers", "logger", "avr"), lambda out: build(LOGGER, "avr", out, "--sim"))
    host = build_cache.get(("handlers", "logger", "host"), lambda out: build(LOGGER, "host", out))
    return avr, host


def test_the_logger_brings_its_sensor_driver_and_runs_alike_on_the_avr_the_host_and_locally(logger, tmp_path):
    avr, host = logger
    args = ["--fast", "--duration", "4s", "--stimulus", LOGGER_STIMULUS]
    run(avr.simulator, *args, "--trace", tmp_path / "avr.csv", "--chips", tmp_path)
    run(host.executable, *args, "--trace", tmp_path / "host.csv")
    interpret(LOGGER, *args, "--trace", tmp_path / "local.csv", cache=tmp_path / "cache")
    host_trace = (tmp_path / "host.csv").read_bytes()
    assert (tmp_path / "avr.csv").read_bytes() == host_trace
    assert (tmp_path / "local.csv").read_bytes() == host_trace
    # The sensor's handlers converted the stimulus (1/16 degC counts) to 0.1 degC.
    _, rows = trace_rows(tmp_path / "host.csv")
    by_time = {int(r["time_us"]): r for r in rows}
    assert by_time[0]["board_temp.temperature"] == "235"  # 376 / 16 = 23.5 degC
    assert by_time[3000000]["board_temp.temperature"] == "312"  # 500 / 16 = 31.25 degC


def _published_records(trace: Path) -> list[list[int]]:
    """log.record at each instant it changed: the records written, in order
    (the statistics' deadlines are 1 s apart and their values differ)."""
    _, rows = trace_rows(trace)
    records, last = [], None
    for r in rows:
        record = [int(r[f"log.record[{k}]"]) for k in range(4)]
        if int(r["time_us"]) % 1000000 == 0 and int(r["time_us"]) > 0 and record != last:
            records.append(record)
        last = record
    return records


def test_the_logger_writes_its_records_to_the_i2c_eeprom_and_goes_on_after_a_reset(logger, tmp_path):
    avr, _host = logger
    args = ["--fast", "--duration", "4s", "--stimulus", LOGGER_STIMULUS, "--chips", tmp_path]
    run(avr.simulator, *args, "--trace", tmp_path / "first.csv")
    image = (tmp_path / "log.bin").read_bytes()
    assert len(image) == 32768
    first = eeprom_log(image, values=4, slot=16)
    published = _published_records(tmp_path / "first.csv")
    assert len(published) == 3
    assert first == [(seq, record) for seq, record in enumerate(published)]
    assert published[2] == [625, 1056, 867, 240]  # min, max, mean of the third second; 24.0 degC
    # A second run (a reset) finds the newest record and goes on after it.
    run(avr.simulator, *args, "--trace", tmp_path / "second.csv")
    second = eeprom_log((tmp_path / "log.bin").read_bytes(), values=4, slot=16)
    assert second[:3] == first
    assert second[3:] == [(3 + k, record) for k, record in enumerate(_published_records(tmp_path / "second.csv"))]


BUSY = dedent("""\
    model busy
    import std
    device room: I2cTemperature(address = 0x4a)
    device log: I2cEepromLog(address = 0x53, values = 2)
    var t: int16
    dataflow D {
        u = Upsample<int16>(factor = 2)
        room.temperature -> t
        room.temperature -> u.x
        u.y -> log.record
    }
    task fast period 1 ms { run D }
    """)


@pytest.fixture(scope="module")
def busy(tmp_path_factory):
    """BUSY built for the AVR (--sim) and the host."""
    folder = tmp_path_factory.mktemp("busy")
    path = write_model(folder, BUSY)
    return build(path, "avr", folder / "avr", "--sim"), build(path, "host", folder / "host")


def test_a_sensor_is_read_at_every_instant_while_the_eeprom_is_busy_writing(busy, tmp_path):
    """A record every millisecond: the EEPROM's 5 ms write cycle refuses the
    next ones (polled again behind the sensor's reads, later ones dropped),
    and every sensor read still gets through at its instant."""
    avr, host = busy
    stim = tmp_path / "s.csv"
    stim.write_text("time_us,room.temperature\n" + "".join(f"{t * 1000},{t * 3 - 200}\n" for t in range(0, 60, 3)))
    args = ["--fast", "--duration", "60ms", "--stimulus", stim]
    run(avr.simulator, *args, "--trace", tmp_path / "avr.csv", "--chips", tmp_path)
    run(host.executable, *args, "--trace", tmp_path / "host.csv")
    assert (tmp_path / "avr.csv").read_bytes() == (tmp_path / "host.csv").read_bytes()
    stored = eeprom_log((tmp_path / "log.bin").read_bytes(), values=2, slot=8)
    _, rows = trace_rows(tmp_path / "host.csv")
    published = [[int(r["log.record[0]"])] * 2 for r in rows]
    assert 6 <= len(stored) <= 15  # about one in five: the write cycle takes 5 ms
    assert [seq for seq, _ in stored] == list(range(len(stored)))
    assert all(record in published for _, record in stored)


PROBE = dedent("""\
    model probe
    import std
    // A driver that reports how its transfer ended (runtime_c/el_bus.h): it
    // writes a register pointer of `width` bytes, then reads `count` bytes.
    device type Probe(address: uint8, width: uint8 = 1, count: uint8 = 2) {
        claims i2c[0] addr address
        out value: int16   // the first datum: the stimulus gives the sensor there its temperature
        out status: uint8
        driver "probe" impl BOARD "probe.c"
    }
    device there: Probe(address = 0x48)
    device absent: Probe(address = 0x60)
    device memory: Probe(address = 0x50, width = 2, count = 100)
    var s1: uint8
    var s2: uint8
    var s3: uint8
    dataflow D { there.status -> s1  absent.status -> s2  memory.status -> s3 }
    task t period 5 ms { run D }
    """)
PROBE_C = dedent("""\
    EL_READ {
        static const uint8_t pointer[2] = {0u, 0u};
        static uint8_t reg[255];
        status = el_i2c_transfer(0u, address, pointer, width, reg, count);
        if (status == EL_BUS_DONE) {
            value = (int16_t)(uint16_t)((uint16_t)reg[0] << 8 | reg[1]);
        }
    }
    """)


def _probe_run(tmp_path: Path, board: str, board_path: list[str]) -> dict[str, str]:
    path = write_model(tmp_path, PROBE.replace("BOARD", board), {"probe.c": PROBE_C})
    extra = [a for p in board_path for a in ("--board-path", p)]
    built = build(path, board, tmp_path / "out", "--sim", *extra)
    stim = tmp_path / "s.csv"
    stim.write_text("time_us,there.value\n0,100\n")
    run(built.simulator, "--fast", "--duration", "20ms", "--stimulus", stim, "--trace", tmp_path / "t.csv")
    return trace_rows(tmp_path / "t.csv")[1][-1]


def test_a_chip_that_is_not_there_does_not_acknowledge(tmp_path):
    last = _probe_run(tmp_path, "avr", [])
    assert (last["there.status"], last["absent.status"], last["memory.status"]) == ("0", "2", "0")  # DONE, NACK
    assert last["there.value"] == str(100 << 4)  # the temperature register: 100/16 degC, left-justified
    assert last["memory.value"] == str(-1)  # erased EEPROM bytes


def test_a_transfer_longer_than_the_bound_is_abandoned_and_the_bus_goes_on(tmp_path):
    """A copy of the AVR board whose jobs wait 300 us at the most: reading
    100 bytes of the EEPROM takes longer, is abandoned (EL_BUS_TIMEOUT) and
    the TWI reset; the sensor's read, behind it, still gets through."""
    folder = tmp_path / "boards" / "avr_wait"
    shutil.copytree(ROOT / "boards" / "avr", folder, ignore=shutil.ignore_patterns("__pycache__"))
    toml = folder / "board.toml"
    toml.write_text(toml.read_text().replace('name = "avr"', 'name = "avr_wait"').replace("wait_us = 2000",
                                                                                          "wait_us = 300"))
    last = _probe_run(tmp_path / "m", "avr_wait", [str(tmp_path / "boards")])
    assert (last["there.status"], last["absent.status"], last["memory.status"]) == ("0", "2", "3")  # TIMEOUT
    assert last["there.value"] == str(100 << 4)


def test_the_simulator_refuses_a_temperature_the_sensor_cannot_measure(busy, tmp_path):
    avr, _host = busy
    stim = tmp_path / "s.csv"
    stim.write_text("time_us,room.temperature\n0,100\n3000,2401\n")
    proc = run(avr.simulator, "--fast", "--duration", "10ms", "--stimulus", stim, ok=False)
    assert proc.returncode == 1
    assert "room (chip model): temperature = 2401: the TMP102-class sensor at i2c[0] 0x4a measures -55 .. 150 " \
           "degC (-880 .. 2400 sixteenths)" in proc.stderr
    assert "room.temperature: the stimulus at 3000 us gives the chip model a value it refuses" in proc.stderr
    (tmp_path / "chips").mkdir()
    (tmp_path / "chips" / "log.bin").write_bytes(b"\xff" * 100)
    proc = run(avr.simulator, "--fast", "--duration", "10ms", "--chips", tmp_path / "chips", ok=False)
    assert proc.returncode == 2
    assert "log.bin is not the 32768-byte memory of 'log'" in proc.stderr


SPI = dedent("""\
    model spi
    import std
    // A device of the model's on the SPI bus: the status register of a
    // 25LC-class chip behind its chip select (RDSR), through EL_CS.
    device type SpiStatus(cs: string) {
        claims spi[0] cs cs
        out status: uint8
        driver "spi_status" impl avr "spi_status.c"
    }
    device log: SpiEepromLog(cs = "PB1", values = 2)
    device nothing: SpiStatus(cs = "PD7")
    device room: I2cTemperature()
    var s: uint8
    dataflow D {
        u = Upsample<int16>(factor = 2)
        room.temperature -> u.x
        u.y -> log.record
        nothing.status -> s
    }
    task t period 10 ms { run D }
    """)
SPI_STATUS_C = dedent("""\
    EL_OPEN {
        (void)el_spi_open(0u, EL_CS);
    }
    EL_READ {
        uint8_t io[2] = {0x05u, 0xFFu};
        (void)el_spi_transfer(0u, EL_CS, EL_SPI_MODE0, io, io, 2u);
        status = io[1];
    }
    """)


def test_the_spi_bus_carries_an_eeprom_log_and_a_devices_own_handlers(tmp_path):
    """The log's records reach the SPI EEPROM model behind PB1; the model's
    own device reads 0xFF from a chip select nothing answers (the host
    simulates it with the same value from the stimulus; the simulator,
    with no hardware behind that device, refuses a column of it)."""
    path = write_model(tmp_path, SPI, {"spi_status.c": SPI_STATUS_C})
    avr = build(path, "avr", tmp_path / "avr", "--sim")
    host = build(path, "host", tmp_path / "host")
    stim, both = tmp_path / "s.csv", tmp_path / "both.csv"
    stim.write_text("time_us,room.temperature\n0,100\n25000,-200\n")
    both.write_text("time_us,room.temperature,nothing.status\n0,100,255\n25000,-200,\n")
    args = ["--fast", "--duration", "50ms"]
    refused = run(avr.simulator, *args, "--stimulus", both, ok=False)
    assert refused.returncode == 2 and refused.stderr.startswith(
        f"{both}:1: column 'nothing.status': nothing reads it: the simavr simulator has no hardware behind device "
        "nothing (the model's handlers, driver spi_status)\n"), refused.stderr
    run(avr.simulator, *args, "--stimulus", stim, "--trace", tmp_path / "avr.csv", "--chips", tmp_path)
    run(host.executable, *args, "--stimulus", both, "--trace", tmp_path / "host.csv")
    assert (tmp_path / "avr.csv").read_bytes() == (tmp_path / "host.csv").read_bytes()
    _, rows = trace_rows(tmp_path / "host.csv")
    assert rows[-1]["s"] == "255"
    stored = eeprom_log((tmp_path / "log.bin").read_bytes(), values=2, slot=8)
    # Records at the deadlines 10 .. 50 ms (the last one goes out at the instant the run ends).
    assert stored == [(0, [100, 100]), (1, [100, 100]), (2, [100, 100]), (3, [-200, -200]), (4, [-200, -200])]


def test_a_chip_select_nothing_answers_reads_0xff_without_any_chip_modelled(tmp_path):
    """The idle MISO line reads 0xFF whatever else the model has: here no
    chip at all that the harness models (it read 0x00 then)."""
    text = SPI
    for line in ('device log: SpiEepromLog(cs = "PB1", values = 2)\n', "device room: I2cTemperature()\n",
                 "    u = Upsample<int16>(factor = 2)\n", "    room.temperature -> u.x\n", "    u.y -> log.record\n"):
        assert line in text
        text = text.replace(line, "")
    path = write_model(tmp_path, text, {"spi_status.c": SPI_STATUS_C})
    avr = build(path, "avr", tmp_path / "avr", "--sim")
    run(avr.simulator, "--fast", "--duration", "30ms", "--trace", tmp_path / "avr.csv")
    _, rows = trace_rows(tmp_path / "avr.csv")
    assert rows[-1]["s"] == "255"


SIZES = dedent("""\
    model sizes
    import std
    device room: I2cTemperature()
    device small: I2cEepromLog(address = 0x51, values = 1, bytes = 4096, page = 32)
    device tiny: SpiEepromLog(cs = "PB1", values = 1, bytes = 2048, page = 16)
    dataflow D { room.temperature -> small.record  room.temperature -> tiny.record }
    task t period 10 ms { run D }
    """)


def test_the_std_chip_models_take_their_size_from_the_devices_parameters(tmp_path):
    """The EEPROM chip models read `bytes` and `page` of their device
    (el_chip_param): each memory in --chips DIR is the device's size, named
    after the device, and holds its records."""
    path = write_model(tmp_path, SIZES)
    avr = build(path, "avr", tmp_path / "avr", "--sim")
    stim = tmp_path / "s.csv"
    stim.write_text("time_us,room.temperature\n0,321\n")
    run(avr.simulator, "--fast", "--duration", "35ms", "--stimulus", stim, "--chips", tmp_path)
    small, tiny = (tmp_path / "small.bin").read_bytes(), (tmp_path / "tiny.bin").read_bytes()
    assert (len(small), len(tiny)) == (4096, 2048)
    assert eeprom_log(small, values=1, slot=4)[:2] == [(0, [321]), (1, [321])]
    assert eeprom_log(tiny, values=1, slot=4)[:2] == [(0, [321]), (1, [321])]
