"""The PIC18's MSSP run for real: handler files of the model's own on its
I2C and SPI buses, the firmware (sdcc) in gpsim, whose harness plays the
MSSP's registers against the chips of its table (sim/sim_chips.h). With no
chip an address nobody acknowledges is a NACK and a chip select reads
0xFF, as on the AVR in simavr (the same model, the same trace); a chip
model linked into the harness answers through the MSSP."""

from __future__ import annotations

import sys
from pathlib import Path
from textwrap import dedent

from easylab.board.registry import load_board
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


# Chip models of the tests' own (sim/el_chip.h), each linked into the harness
# with a one-entry table written by hand.
SPI_CHIP_C = dedent("""\
    #define EL_CHIP test_spi_chip
    #include "el_chip.h"

    /* Answers MOSI's first byte inverted in its high nibble, then how
     * often it has been selected. */
    typedef struct { uint8_t k; uint8_t selects; } spi_chip_t;

    static void on_select(el_chip_t *chip, bool selected)
    {
        spi_chip_t *s = chip->state;
        if (selected) {
            s->k = 0u;
            s->selects++;
        }
    }

    static uint8_t on_byte(el_chip_t *chip, uint8_t mosi)
    {
        spi_chip_t *s = chip->state;
        return s->k++ == 0u ? (uint8_t)(mosi ^ 0xF0u) : s->selects;
    }

    const el_chip_ops_t EL_CHIP = {
        .name = "spi_chip", .state_size = sizeof(spi_chip_t), .spi_select = on_select, .spi_byte = on_byte,
    };
    """)
SPI_TABLE_C = dedent("""\
    #include "sim_chips.h"
    extern const el_chip_ops_t test_spi_chip;
    const sim_chip_entry_t sim_chip_table[1] = {
        { &test_spi_chip, SIM_CHIP_SPI, 0u, 0u, 0x1Fu, "RD7", "adc", 0u, 0, 0u, 0, 0, 0u, 0 }, /* RD7: port D (3) << 3 | 7 */
    };
    const uint16_t sim_chip_table_count = 1u;
    """)
I2C_CHIP_C = dedent("""\
    #define EL_CHIP test_i2c_chip
    #include "el_chip.h"

    /* A register pointer (the first byte written after the address), then
     * bytes pointer * 16 + 1, + 2, ... read from it. */
    typedef struct { uint8_t pointer; uint8_t written; uint8_t next; uint8_t stops; } i2c_chip_t;

    static bool on_start(el_chip_t *chip, bool read)
    {
        i2c_chip_t *s = chip->state;
        if (read) {
            s->next = (uint8_t)(s->pointer * 16u);
        }
        s->written = 0u;
        return true;
    }

    static bool on_write(el_chip_t *chip, uint8_t byte)
    {
        i2c_chip_t *s = chip->state;
        if (s->written++ == 0u) {
            s->pointer = byte;
        }
        return true;
    }

    static uint8_t on_read(el_chip_t *chip)
    {
        i2c_chip_t *s = chip->state;
        return ++s->next;
    }

    static void on_stop(el_chip_t *chip)
    {
        ((i2c_chip_t *)chip->state)->stops++;
    }

    const el_chip_ops_t EL_CHIP = {
        .name = "i2c_chip", .state_size = sizeof(i2c_chip_t), .i2c_start = on_start, .i2c_write = on_write,
        .i2c_read = on_read, .i2c_stop = on_stop,
    };
    """)
I2C_TABLE_C = dedent("""\
    #include "sim_chips.h"
    extern const el_chip_ops_t test_i2c_chip;
    const sim_chip_entry_t sim_chip_table[3] = {
        { &test_i2c_chip, SIM_CHIP_I2C, 0u, 0x60u, 0u, "", "long", 0u, 0, 0u, 0, 0, 0u, 0 },
        { &test_i2c_chip, SIM_CHIP_I2C, 0u, 0x61u, 0u, "", "short", 0u, 0, 0u, 0, 0, 0u, 0 },
        { &test_i2c_chip, SIM_CHIP_I2C, 0u, 0x63u, 0u, "", "writes", 0u, 0, 0u, 0, 0, 0u, 0 },
    };
    const uint16_t sim_chip_table_count = 3u;
    """)


def _harness_with_chips(out: Path, files: dict[str, str]) -> Path:
    """The build's harness again, its empty chip table (simulator.chip_table)
    left out and the chip files and their table linked in."""
    board = load_board("pic18").configure("pic18f4520", sim=True)
    simulator = sys.modules[type(board).__module__].simulator
    source = (out / "sim_model.c").read_text()
    empty = "\n".join(simulator.chip_table(None, board))
    assert empty in source
    chips = []
    for name, text in files.items():
        (out / name).write_text(text)
        chips.append(out / name)
    return simulator.build_harness(board, out, source.replace(empty, ""), out / "chips-sim", chips=tuple(chips))


def test_an_spi_chip_model_answers_through_the_mssp(tmp_path):
    """MOSI reaches the chip, each chip select's fall selects it, its
    answer comes back in SSPBUF: 0x05 ^ 0xF0 = 0xF5, then the count."""
    path = write_model(tmp_path, SPI_MODEL, {"spi_probe.c": SPI_PROBE_C})
    build(path, "pic18", tmp_path / "pic18", "--sim")
    harness = _harness_with_chips(tmp_path / "pic18", {"spi_chip.c": SPI_CHIP_C, "spi_table.c": SPI_TABLE_C})
    trace = tmp_path / "t.csv"
    run(harness, "--fast", "--duration", "20ms", "--trace", trace)
    assert [(r["time_us"], r["adc.value"]) for r in _rows(trace.read_text())] == \
        [(str(t * 5000), str(0xF500 + t + 1)) for t in range(4)]


I2C_CHIP_MODEL = dedent("""\
    model i2c_chip
    import std
    device type Probe(address: uint8, width: uint8 = 1, count: uint8 = 2) {
        claims i2c[0] addr address
        out value: int16
        out status: uint8
        out errors: uint16
        driver "probe" impl pic18 "probe.c"
    }
    device long: Probe(address = 0x60, count = 120)
    device short: Probe(address = 0x61)
    device writes: Probe(address = 0x63, width = 2, count = 0)
    device absent: Probe(address = 0x62)
    var s1: uint8
    var s2: uint8
    var s3: uint8
    var s4: uint8
    dataflow D { long.status -> s1  short.status -> s2  writes.status -> s3  absent.status -> s4 }
    task t period 5 ms { run D }
    """)


def test_an_i2c_chip_model_answers_and_a_transfer_longer_than_the_bound_is_abandoned(tmp_path):
    """The chip at 0x61 takes the register pointer and gives its bytes
    (EL_BUS_DONE), the one at 0x63 takes a write; reading 120 bytes from the one at 0x60 takes 2.6 ms at
    400 kHz, longer than the 2 ms bound: abandoned (EL_BUS_TIMEOUT), the
    MSSP reset, and the reads behind it still get through."""
    path = write_model(tmp_path, I2C_CHIP_MODEL, {"probe.c": PROBE_C})
    build(path, "pic18", tmp_path / "pic18", "--sim")
    harness = _harness_with_chips(tmp_path / "pic18", {"i2c_chip.c": I2C_CHIP_C, "i2c_table.c": I2C_TABLE_C})
    trace = tmp_path / "t.csv"
    run(harness, "--fast", "--duration", "20ms", "--trace", trace)
    rows = _rows(trace.read_text())
    assert len(rows) == 4
    for k, r in enumerate(rows):
        assert (r["long.status"], r["long.errors"]) == ("3", str(k + 1)), r  # EL_BUS_TIMEOUT
        assert (r["short.status"], r["short.errors"], r["short.value"]) == ("0", "0", str(0x0102)), r
        assert (r["writes.status"], r["writes.errors"]) == ("0", "0"), r
        assert (r["absent.status"], r["absent.errors"]) == ("2", str(k + 1)), r  # EL_BUS_NACK


BUSY_CHIP_C = dedent("""\
    #define EL_CHIP test_busy_chip
    #include "el_chip.h"

    /* An EEPROM-like chip: after each transaction it went through (and at
     * start) it does not acknowledge its address once (a write cycle);
     * its bytes are 0xA0, 0xA1, ... */
    typedef struct { uint8_t refuse; bool acked; uint8_t next; } busy_chip_t;

    static void on_reset(el_chip_t *chip) { ((busy_chip_t *)chip->state)->refuse = 1u; }

    static bool on_start(el_chip_t *chip, bool read)
    {
        busy_chip_t *s = chip->state;
        (void)read;
        if (s->refuse != 0u) {
            s->refuse--;
            return false;
        }
        s->acked = true;
        return true;
    }

    static bool on_write(el_chip_t *chip, uint8_t byte)
    {
        (void)chip;
        (void)byte;
        return true;
    }

    static uint8_t on_read(el_chip_t *chip)
    {
        busy_chip_t *s = chip->state;
        return (uint8_t)(0xA0u + s->next++);
    }

    static void on_stop(el_chip_t *chip)
    {
        busy_chip_t *s = chip->state;
        if (s->acked) {
            s->refuse = 1u;
            s->next = 0u;
        }
        s->acked = false;
    }

    const el_chip_ops_t EL_CHIP = {
        .name = "busy_chip", .state_size = sizeof(busy_chip_t), .reset = on_reset, .i2c_start = on_start,
        .i2c_write = on_write, .i2c_read = on_read, .i2c_stop = on_stop,
    };
    """)
BUSY_TABLE_C = dedent("""\
    #include "sim_chips.h"
    extern const el_chip_ops_t test_busy_chip;
    const sim_chip_entry_t sim_chip_table[2] = {
        { &test_busy_chip, SIM_CHIP_I2C, 0u, 0x50u, 0u, "", "patient", 0u, 0, 0u, 0, 0, 0u, 0 },
        { &test_busy_chip, SIM_CHIP_I2C, 0u, 0x51u, 0u, "", "hasty", 0u, 0, 0u, 0, 0, 0u, 0 },
    };
    const uint16_t sim_chip_table_count = 2u;
    """)
BUSY_MODEL = dedent("""\
    model busy
    import std
    // A read that may find its chip busy: with `retry` its job says so
    // (EL_I2C_RETRY_BUSY) and is tried again; without, the NACK is the end.
    device type Memory(at: uint8, retry: bool) {
        claims i2c[0] addr at
        out value: uint16
        out status: uint8
        driver "memory" impl pic18 "memory.c"
    }
    device patient: Memory(at = 0x50, retry = true)
    device hasty: Memory(at = 0x51, retry = false)
    var s1: uint8
    var s2: uint8
    dataflow D { patient.status -> s1  hasty.status -> s2 }
    task t period 5 ms { run D }
    """)
MEMORY_C = dedent("""\
    EL_READ {
        static const uint8_t pointer = 0u;
        static uint8_t reg[2];
        static el_i2c_job_t job; /* zero at boot: EL_BUS_DONE */
        job.bus = 0u;
        job.address = at; /* a parameter named `address` would be a macro here */
        job.flags = retry ? EL_I2C_RETRY_BUSY : 0u;
        job.tx = &pointer;
        job.tx_len = 1u;
        job.rx = reg;
        job.rx_len = 2u;
        (void)el_i2c_submit(&job);
        status = el_i2c_wait(&job);
        value = status == EL_BUS_DONE ? (uint16_t)((uint16_t)reg[0] << 8 | reg[1]) : 0u;
    }
    """)


def test_a_job_that_finds_its_chip_busy_is_tried_again_when_it_says_so(tmp_path):
    """Each chip refuses its address once after every transaction: the
    job flagged EL_I2C_RETRY_BUSY waits parked (the bus idle) and gets
    through at a later Timer2 interrupt, within the instant; the other one
    ends in EL_BUS_NACK, and gets through at every second read."""
    path = write_model(tmp_path, BUSY_MODEL, {"memory.c": MEMORY_C})
    build(path, "pic18", tmp_path / "pic18", "--sim")
    harness = _harness_with_chips(tmp_path / "pic18", {"busy_chip.c": BUSY_CHIP_C, "busy_table.c": BUSY_TABLE_C})
    trace = tmp_path / "t.csv"
    run(harness, "--fast", "--duration", "20ms", "--trace", trace)
    rows = _rows(trace.read_text())
    assert len(rows) == 4
    assert all((r["patient.status"], r["patient.value"]) == ("0", str(0xA0A1)) for r in rows), rows
    assert [(r["hasty.status"], r["hasty.value"]) for r in rows] == [("2", "0"), ("0", str(0xA0A1))] * 2
