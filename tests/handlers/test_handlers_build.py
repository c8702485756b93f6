"""Builds of devices with handlers from the model's folder and devices on
buses: the generated handlers, the boards' checks (a board without handlers
for a device, bus addresses and pins), the host board's fallback."""

from __future__ import annotations

import re
from textwrap import dedent

import pytest

from handlers_testlib import build, cli, run, trace_rows, write_model

TYPE = dedent("""\
    model m
    import std
    device type Gauge(bus: uint8 = 0, address: uint8 = 0x48, scale: int16 = 10) {
        claims i2c[bus] addr address
        out level: int16
        state reads: uint16
        driver "gauge" IMPLS
    }
    """)
GAUGE_HOST = dedent("""\
    /* the stimulus value times the scale (file-scope code sees no device's names) */
    static int16_t scaled(int16_t v, int16_t k) { return (int16_t)(v * k); }
    EL_READ {
        reads++;
        level = scaled(level, scale);
    }
    """)
GAUGE_AVR = dedent("""\
    EL_READ {
        static const uint8_t pointer = 0u;
        uint8_t reg[2];
        if (el_i2c_transfer(bus, address, &pointer, 1u, reg, 2u) == EL_BUS_DONE) {
            level = (int16_t)((int16_t)(uint16_t)((uint16_t)reg[0] << 8 | reg[1]) / 16 * scale);
            reads++;
        }
    }
    """)
USE = dedent("""\
    device a: Gauge()
    device b: Gauge(address = 0x49, scale = 3)
    var x: int16
    var y: int16
    dataflow D { a.level -> x  b.level -> y }
    task t period 10 ms { run D }
    """)


def model(tmp_path, impls: str, files: dict[str, str], use: str = USE):
    return write_model(tmp_path, TYPE.replace("IMPLS", impls) + use, files)


def test_the_generated_handlers_see_the_devices_names_and_keep_their_own_state(tmp_path):
    path = model(tmp_path, 'impl host "gauge_host.c"', {"gauge_host.c": GAUGE_HOST})
    built = build(path, "host", tmp_path / "out")
    text = (tmp_path / "out" / "el_handlers.c").read_text()
    assert text.count("static int16_t scaled(int16_t v, int16_t k)") == 1  # the file's own code once
    for dev, scale in ((0, 10), (1, 3)):
        assert f"static el_mdev{dev}_state_t el_mdev{dev}_state; /* zero at boot */" in text
        assert f"#define scale ((int16_t){scale})" in text
        assert f"#define reads ((el_mdev{dev}_state).reads)" in text
        assert re.search(rf"void el_mdev{dev}_read\(void\)\n{{\n    {{\n#line 3 \"[^\"]*gauge_host\.c\"\n\n    reads\+\+;",
                         text), text
    assert "#define level (el_i2_a_level)" in text and "#define level (el_i3_b_level)" in text
    model_c = (tmp_path / "out" / "model.c").read_text()
    assert "el_sim_sample(0u); { void el_mdev0_read(void); el_mdev0_read(); } /* a */" in model_c
    assert "el_mdev0_open" not in model_c  # a block the file lacks costs nothing
    stim = tmp_path / "s.csv"
    stim.write_text("time_us,a.level,b.level\n0,4,5\n15000,-2,\n")
    run(built.executable, "--fast", "--duration", "30ms", "--stimulus", stim, "--trace", tmp_path / "t.csv")
    _, rows = trace_rows(tmp_path / "t.csv")
    assert [(r["a.level"], r["b.level"]) for r in rows] == [("40", "15"), ("40", "15"), ("-20", "15")]


def test_a_board_without_handlers_for_a_device_refuses_it_saying_what_to_write(tmp_path):
    path = model(tmp_path, 'impl host "gauge_host.c"', {"gauge_host.c": GAUGE_HOST})
    proc = build(path, "avr", tmp_path / "out", ok=False).proc
    assert proc.returncode == 1
    assert proc.stderr.startswith("easylab: error: the model does not fit the avr board with the atmega328p "
                                  "(2 problems):")
    assert (f"{path}:9: error: device 'a' (Gauge, driver 'gauge') has no handlers for the avr board: its type "
            "brings them for host only; write a C file with its EL_OPEN ... EL_CLOSE blocks for the avr board and "
            "name it after the driver: driver \"gauge\" impl avr \"FILE.c\" (docs/boards.md, 'Writing a device "
            "driver')") in proc.stderr
    assert f"{path}:10: error: device 'b' (Gauge," in proc.stderr


def test_a_board_with_a_driver_of_that_name_runs_it_when_the_type_brings_no_file_for_it(tmp_path):
    text = dedent("""\
        model m
        import std
        device type Lamp(pin: string) {
            claims pin[pin]
            in level: bool
            driver "digital_out" impl host "lamp_host.c"
        }
        device lamp: Lamp(pin = "PB5")
        dataflow D { w = SquareWave(half_period = 2)  w.y -> lamp.level }
        task t period 10 ms { run D }
        """)
    path = write_model(tmp_path, text, {"lamp_host.c": "EL_WRITE { (void)level; }\n"})
    build(path, "avr", tmp_path / "avr")
    assert not (tmp_path / "avr" / "el_handlers.c").exists()
    assert "el_drv_digital_out_write(&el_dev0);" in (tmp_path / "avr" / "model.c").read_text()


def test_the_host_simulates_a_device_whose_type_brings_no_host_handlers(tmp_path):
    path = model(tmp_path, 'impl avr "gauge_avr.c"', {"gauge_avr.c": GAUGE_AVR})
    built = build(path, "host", tmp_path / "out")
    assert not (tmp_path / "out" / "el_handlers.c").exists()
    stim = tmp_path / "s.csv"
    stim.write_text("time_us,a.level,b.level\n0,4,5\n")
    run(built.executable, "--fast", "--duration", "20ms", "--stimulus", stim, "--trace", tmp_path / "t.csv")
    _, rows = trace_rows(tmp_path / "t.csv")
    assert (rows[0]["a.level"], rows[0]["b.level"]) == ("4", "5")


@pytest.mark.parametrize("content, place, message", [
    ("EL_READ { }\n  EL_STEP { }\n", "2:3", r"EL_STEP is not a block of this file; its blocks are EL_OPEN, "
                                           r"EL_START, EL_READ, EL_WRITE, EL_STOP, EL_CLOSE"),
    ("EL_READ { }\nEL_READ { }\n", "2:1", r"EL_READ is given twice"),
    ("EL_WRITE x;\n", "1:1", r"EL_WRITE must be followed by a block \{ \.\.\. \}"),
    ("\n\nEL_OPEN {\n", "3:9", r"the block of EL_OPEN is never closed"),
])
def test_a_malformed_handler_file_is_refused_by_the_checker_at_its_place(tmp_path, content, place, message):
    """What can be seen without compiling a handler file is an error of
    `easylab check` (and so of every build) at the file's line and column,
    with a note at the model's line that names the file."""
    path = model(tmp_path, 'impl host "gauge_host.c"', {"gauge_host.c": content})
    proc = cli("check", path)
    assert proc.returncode == 1 and re.search(rf"gauge_host\.c:{place}: error: {message}\n.*model\.elab:7:20: note: the handler file "
                     rf"'gauge_host\.c' is named here", proc.stderr, re.S), proc.stderr
    err = build(path, "host", tmp_path / "out", ok=False).proc.stderr
    assert re.search(rf"gauge_host\.c:{place}: error: {message}", err), err


def test_a_compiler_error_in_a_handler_names_the_users_file_and_line(tmp_path):
    path = model(tmp_path, 'impl host "gauge_host.c"',
                 {"gauge_host.c": "/* one */\nEL_READ {\n    reads++;\n    level = not_declared;\n}\n"})
    err = build(path, "host", tmp_path / "out", ok=False).proc.stderr
    assert re.search(r"gauge_host\.c:4:\d+: error: .not_declared. undeclared", err), err
    assert "el_handlers.c:" not in err


def test_a_state_its_handler_file_does_not_use_builds_on_every_board(tmp_path):
    """A failure counter only the real driver counts: the host's handler
    file never names it, and the build is no error."""
    path = model(tmp_path, 'impl host "gauge_host.c" impl avr "gauge_avr.c"',
                 {"gauge_host.c": "EL_READ { level = 4; }\n", "gauge_avr.c": GAUGE_AVR})
    built = build(path, "host", tmp_path / "host")
    build(path, "avr", tmp_path / "avr", "--mcu", "atmega328p")
    run(built.executable, "--fast", "--duration", "20ms", "--trace", tmp_path / "t.csv")
    _, rows = trace_rows(tmp_path / "t.csv")
    assert rows[-1]["a.level"] == "4"


@pytest.mark.parametrize("use, problem", [
    ('device a: Gauge(address = 0x05)\nvar x: int16\ndataflow D { a.level -> x }\ntask t period 10 ms { run D }\n',
     "device 'a' claims i2c[0] addr 0x05, but I2C leaves addresses 0x08..0x77 to devices (7 bits; the others are "
     "reserved)"),
    ('device a: Gauge(bus = 1)\nvar x: int16\ndataflow D { a.level -> x }\ntask t period 10 ms { run D }\n',
     "device 'a' claims i2c[1] addr 0x48, but the atmega328p has no I2C bus 1 (I2C buses: i2c[0])"),
    ('device a: Gauge()\ndevice led: DigitalOut(pin = "PC4")\nvar x: int16\n'
     'dataflow D { a.level -> x  w = SquareWave(half_period = 2)  w.y -> led.level }\n'
     'task t period 10 ms { run D }\n',
     "pin PC4 is claimed twice on the atmega328p: as pin[\"PC4\"] by device 'led' and as i2c[0] addr 0x48 by "
     "device 'a'"),
])
def test_the_avr_board_checks_the_bus_claims(tmp_path, use, problem):
    path = model(tmp_path, 'impl avr "gauge_avr.c"', {"gauge_avr.c": GAUGE_AVR}, use)
    err = build(path, "avr", tmp_path / "out", ok=False).proc.stderr
    assert problem in err, err


def test_devices_on_one_bus_share_its_pins_on_the_avr(tmp_path):
    path = model(tmp_path, 'impl avr "gauge_avr.c"', {"gauge_avr.c": GAUGE_AVR})
    build(path, "avr", tmp_path / "out")
    config = (tmp_path / "out" / "el_avr_config.h").read_text()
    assert "/* i2c[0] on the TWI: device 'a', device 'b' */" in config
    assert "#define EL_AVR_I2C_PULLUPS (_BV(4) | _BV(5))" in config


def test_an_eeprom_log_whose_record_does_not_fit_a_page_is_refused(tmp_path):
    text = dedent("""\
        model m
        import std
        device log: I2cEepromLog(values = 40)
        dataflow D { u = Upsample<int16>(factor = 40)  c = Const<int16>(value = 1)  c.y -> u.x  u.y -> log.record }
        task t period 10 ms { run D }
        """)
    err = build(write_model(tmp_path, text), "avr", tmp_path / "out", ok=False).proc.stderr
    assert "error: device 'log': a record of 40 values takes a slot of 128 bytes, which must divide its page of " \
           "64 bytes" in err, err


@pytest.mark.parametrize("cs, problem", [
    ("PB5", "device 'log' claims spi[0] cs \"PB5\", but PB5 is the bus's SCK: a chip select is a pin of its own "
            "(or the bus SS, PB2)"),
    ("PX1", "device 'log' claims spi[0] cs \"PX1\", but its chip select PX1 is not a pin of the atmega328p"),
])
def test_the_avr_board_checks_chip_selects(tmp_path, cs, problem):
    text = dedent(f"""\
        model m
        import std
        device log: SpiEepromLog(cs = "{cs}", values = 1)
        dataflow D {{ c = Const<int16>(value = 1)  c.y -> log.record }}
        task t period 10 ms {{ run D }}
        """)
    err = build(write_model(tmp_path, text), "avr", tmp_path / "out", ok=False).proc.stderr
    assert problem in err, err


def test_the_pic18_board_builds_handler_files_with_sdcc(tmp_path):
    """A device that brings handlers for the PIC18 runs them: el_handlers.c
    goes through sdcc (the board's passes, as model.c does), model.c calls
    the functions el_pic18_devices.h declares (sdcc takes no declaration
    inside a block), and the MSSP is the I2C master its handlers use."""
    path = model(tmp_path, 'impl pic18 "gauge_pic18.c"', {"gauge_pic18.c": GAUGE_AVR})
    build(path, "pic18", tmp_path / "out")
    out = tmp_path / "out"
    assert "void el_mdev0_read(void)\n{" in (out / "el_handlers.c").read_text()
    assert "void el_mdev1_read(void);" in (out / "el_pic18_devices.h").read_text()
    assert "{ el_mdev0_read(); /* a */ }" in (out / "model.c").read_text()
    config = (out / "el_pic18_config.h").read_text()
    assert "/* i2c[0] on the MSSP: device 'a', device 'b' */" in config
    assert "#define EL_PIC18_I2C_SSPADD 24u /* 400000 Hz */" in config
    assert (out / "m.hex").is_file()


def test_a_compiler_error_in_a_pic18_handler_names_the_users_file_and_line(tmp_path):
    path = model(tmp_path, 'impl pic18 "gauge_pic18.c"',
                 {"gauge_pic18.c": "/* one */\nEL_READ {\n    reads++;\n    level = not_declared;\n}\n"})
    err = build(path, "pic18", tmp_path / "out", ok=False).proc.stderr
    assert re.search(r"gauge_pic18\.c:4: error \d+: .*not_declared", err), err


SPI_TYPE = dedent("""\
    device type SpiStatus(cs: string) {
        claims spi[0] cs cs
        out status: uint8
        driver "spi_status" impl pic18 "spi_status.c"
    }
    """)


@pytest.mark.parametrize("use, problem", [
    ('device a: Gauge()\ndevice adc: SpiStatus(cs = "RB2")\nvar x: int16\nvar s: uint8\n'
     'dataflow D { a.level -> x  adc.status -> s }\ntask t period 10 ms { run D }\n',
     "model.elab:15: error: device 'adc' claims spi[0] cs \"RB2\", but the pic18f4520's i2c[0] and spi[0] are one "
     "MSSP, which device 'a' (MODEL:14) uses as i2c[0] addr 0x48: a model uses the MSSP as one bus, i2c[0] or "
     "spi[0]"),
    ('device adc: SpiStatus(cs = "RC3")\nvar s: uint8\ndataflow D { adc.status -> s }\ntask t period 10 ms { run D }\n',
     "device 'adc' claims spi[0] cs \"RC3\", but RC3 is the bus's SCK: a chip select is a pin of its own"),
    ('device a: Gauge()\ndevice led: DigitalOut(pin = "RC4")\nvar x: int16\n'
     'dataflow D { a.level -> x  w = SquareWave(half_period = 2)  w.y -> led.level }\n'
     'task t period 10 ms { run D }\n',
     "pin RC4 is claimed twice on the pic18f4520: as pin[\"RC4\"] by device 'led' and as i2c[0] addr 0x48 by "
     "device 'a'"),
])
def test_the_pic18_board_checks_the_mssp_claims(tmp_path, use, problem):
    """I2C and SPI share the MSSP's pins (SCL is SCK, SDA is SDI): a model
    uses one of them, and the message names both devices."""
    path = model(tmp_path, 'impl pic18 "gauge_pic18.c"', {"gauge_pic18.c": GAUGE_AVR,
                                                          "spi_status.c": "EL_READ { status = 0u; }\n"},
                 SPI_TYPE + use)
    err = build(path, "pic18", tmp_path / "out", ok=False).proc.stderr
    assert problem.replace("MODEL", str(path)) in err, err
    assert "Traceback" not in err
