"""The PIC18's MSSP run for real: handler files of the model's own on its
I2C and SPI buses, the firmware (sdcc) in gpsim, whose harness plays the
MSSP's registers against the chips of its table (sim/sim_chips.h). With no
chip an address nobody acknowledges is a NACK and a chip select reads
0xFF, as on the AVR in simavr (the same model, the same trace); a chip
model linked into the harness answers through the MSSP."""

from __future__ import annotations

from pathlib import Path
from textwrap import dedent

from firmware_builds import build, write_model
from pic18_testlib import run

I2C_MODEL = dedent("""\
    model i2c
    import std
    // A driver that reports how its transfer ended (runtime_c/el_bus.h) and
    // counts the failed ones: it writes `width` bytes, then reads `count`.
    device type Probe(address: uint8, width: uint8 = 1, count: uint8 = 2) {
        claims i2c[0] addr address
        out value: int16
        out status: uint8
        out errors: uint16
        driver "probe" impl pic18 "probe.c" impl avr "probe.c"
    }
    device both: Probe(address = 0x60)
    device reads: Probe(address = 0x21, width = 0)
    device writes: Probe(address = 0x70, width = 2, count = 0)
    var s1: uint8
    var s2: uint8
    var s3: uint8
    dataflow D { both.status -> s1  reads.status -> s2  writes.status -> s3 }
    task t period 5 ms { run D }
    """)
PROBE_C = dedent("""\
    EL_READ {
        static const uint8_t pointer[2] = {0u, 0u};
        static uint8_t reg[128];
        status = el_i2c_transfer(0u, address, pointer, width, reg, count);
        if (status == EL_BUS_DONE) {
            value = (int16_t)(uint16_t)((uint16_t)reg[0] << 8 | reg[1]);
        } else {
            errors++;
        }
    }
    """)

SPI_MODEL = dedent("""\
    model spi
    import std
    // A device on the SPI bus behind its own chip select (EL_CS): two bytes
    // in mode 0, the second one kept. PD7 is RD7 on the PIC18.
    device type SpiProbe(cs: string) {
        claims spi[0] cs cs
        out value: uint16
        driver "spi_probe" impl pic18 "spi_probe.c" impl avr "spi_probe.c"
    }
    device adc: SpiProbe(cs = "PD7")
    var v: uint16
    dataflow D { adc.value -> v }
    task t period 5 ms { run D }
    """)
SPI_PROBE_C = dedent("""\
    EL_OPEN {
        (void)el_spi_open(0u, EL_CS);
    }
    EL_READ {
        uint8_t io[2] = {0x05u, 0xFFu};
        if (el_spi_transfer(0u, EL_CS, EL_SPI_MODE0, io, io, 2u) == EL_BUS_DONE) {
            value = (uint16_t)((uint16_t)io[0] << 8 | io[1]);
        }
    }
    """)


def _trace(built, tmp_path: Path, name: str) -> str:
    trace = tmp_path / f"{name}.csv"
    run(built.simulator, "--fast", "--duration", "20ms", "--trace", trace)
    return trace.read_text()


def _rows(text: str) -> list[dict[str, str]]:
    lines = text.splitlines()
    header = lines[0].split(",")
    return [dict(zip(header, line.split(","))) for line in lines[1:]]


def test_an_i2c_address_nobody_acknowledges_is_a_nack_on_the_pic18_as_on_the_avr(tmp_path):
    """Every kind of transfer (write then read, read only, write only) to
    an address without a chip ends in EL_BUS_NACK, at every read; the
    handler counts them, and the trace is the AVR's in simavr."""
    path = write_model(tmp_path, I2C_MODEL, {"probe.c": PROBE_C})
    pic = build(path, "pic18", tmp_path / "pic18", "--sim")
    avr = build(path, "avr", tmp_path / "avr", "--sim")
    text = _trace(pic, tmp_path, "pic18")
    rows = _rows(text)
    assert [r["time_us"] for r in rows] == ["0", "5000", "10000", "15000"]
    for k, r in enumerate(rows):
        for dev in ("both", "reads", "writes"):
            assert (r[f"{dev}.status"], r[f"{dev}.errors"]) == ("2", str(k + 1)), r  # EL_BUS_NACK
    assert text == _trace(avr, tmp_path, "avr")


def test_a_chip_select_nothing_answers_reads_0xff_on_the_pic18_as_on_the_avr(tmp_path):
    path = write_model(tmp_path, SPI_MODEL, {"spi_probe.c": SPI_PROBE_C})
    pic = build(path, "pic18", tmp_path / "pic18", "--sim")
    avr = build(path, "avr", tmp_path / "avr", "--sim")
    text = _trace(pic, tmp_path, "pic18")
    assert _rows(text)[-1]["adc.value"] == str(0xFFFF)
    assert text == _trace(avr, tmp_path, "avr")
    assert "#define EL_PIC18_SPI_SSPM 1u /* Fosc / 16: 2500000 Hz */" in \
        (tmp_path / "pic18" / "el_pic18_config.h").read_text()
