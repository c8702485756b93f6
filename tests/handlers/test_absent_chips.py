"""Where no chip answers on a simulated bus (docs/boards.md, "Chip
models"): one behaviour whatever else the model has, here on the AVR in
simavr. A chip select nobody answers reads 0xFF (the idle MISO, pulled
up); an I2C address nobody acknowledges is a NACK the handler sees
(EL_BUS_NACK), in a model without any chip the harness runs and in one
with chip models of its own and std chips on the same buses."""

from __future__ import annotations

from pathlib import Path
from textwrap import dedent

import pytest

from handlers_testlib import build, run, trace_rows, write_model

OWN = Path(__file__).with_name("own_chips")

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
# Chip models of the model's own (tests/handlers/own_chips/), and std's chips.
OTHERS = dedent("""\
    device type Mcp3201(cs: string = "PB2") {
        claims spi[0] cs cs
        out value: uint16
        driver "mcp3201" impl avr "drivers/mcp3201_mcu.c" sim "drivers/mcp3201_chip.c"
    }
    device type Hygro(bus: uint8 = 0, address: uint8 = 0x28) {
        claims i2c[bus] addr address
        out humidity: uint16
        state failures: uint16
        driver "hygro" impl avr "drivers/hygro_mcu.c" sim "drivers/hygro_chip.c"
    }
    device adc: Mcp3201()
    device hygro: Hygro()
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
