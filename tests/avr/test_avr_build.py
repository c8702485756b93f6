"""The AVR board's builds: every example for the ATmega2560, blink and
cd_to_dat for the ATmega328P, sizes in the output, the resource and driver
checks with their messages, the tick timer, the make targets."""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest

from avr_testlib import EXAMPLE_NAMES, ROOT, avr_build, cli

SIZE_LINE = re.compile(r"^(atmega\w+): flash (\d+) of (\d+) bytes .*RAM (\d+) of (\d+) bytes")


def sizes(built) -> dict:
    m = SIZE_LINE.match(built.size_line)
    assert m, built.proc.stdout
    return {"mcu": m.group(1), "flash": int(m.group(2)), "flash_max": int(m.group(3)), "ram": int(m.group(4)),
            "ram_max": int(m.group(5))}


def write_model(tmp_path: Path, name: str, body: str) -> Path:
    path = tmp_path / f"{name}.elab"
    path.write_text(f"model {name}\nimport std\n\n{body}", encoding="utf-8")
    return path


# ---------------------------------------------------------------- examples


@pytest.mark.parametrize("name", EXAMPLE_NAMES)
def test_every_example_builds_for_the_atmega2560(sim_builds, name):
    built = sim_builds[name]
    s = sizes(built)
    assert s["mcu"] == "atmega2560" and s["flash_max"] == 262144 - 8192 and s["ram_max"] == 8192
    assert 0 < s["flash"] < s["flash_max"] and 0 < s["ram"] < s["ram_max"]
    # The ELF's path is the last line, the .hex lies beside it without
    # simavr's .mmcu section (which sits at 0x910000).
    assert built.lines[-1] == str(built.elf)
    hexfile = built.elf.with_suffix(".hex")
    assert hexfile.is_file()
    records = [line for line in hexfile.read_text().splitlines() if line.startswith(":")]
    assert records[-1] == ":00000001FF"
    assert not any(r[7:9] == "04" and r[9:13] == "0091" for r in records)  # no extended address 0x0091xxxx


def test_release_builds_leave_out_the_debug_interface(tmp_path):
    debug_build = avr_build(ROOT / "examples/blink.elab", tmp_path / "d")
    release_build = avr_build(ROOT / "examples/blink.elab", tmp_path / "r", "--release")

    def symbols(built) -> set[str]:
        out = subprocess.run(["avr-nm", str(built.elf)], capture_output=True, text=True, check=True).stdout
        return {line.split()[-1] for line in out.splitlines() if line.strip()}

    assert {"el_debug_poll", "el_debug_probe", "el_debug_instant"} <= symbols(debug_build)
    assert not {s for s in symbols(release_build) if s.startswith("el_debug_")}
    debug, release = sizes(debug_build), sizes(release_build)
    # The 328P's debug server (its buffers sized from the model, 138 bytes of RAM) and the debug
    # UART's receive ring (33) and transmit pointer: blink's debug build has more than 200 bytes
    # of RAM over its release build.
    assert release["flash"] < debug["flash"] - 2000 and release["ram"] < debug["ram"] - 200


def test_blink_builds_for_the_atmega328p_by_default(tmp_path):
    built = avr_build(ROOT / "examples/blink.elab", tmp_path / "b")
    s = sizes(built)
    assert s["mcu"] == "atmega328p" and s["flash_max"] == 32768 - 512 and s["ram_max"] == 2048
    assert s["ram"] + 256 <= 2048


def test_cd_to_dat_does_not_fit_the_atmega328p_with_its_own_schedule(tmp_path):
    # A debug build: the release build fits since it links no service map
    # (cd_to_dat has no Modbus interface), 1,760 bytes of RAM.
    built = avr_build(ROOT / "examples/cd_to_dat.elab", tmp_path / "c", ok=False)
    err = built.proc.stderr
    assert "does not fit the atmega328p's 2048 bytes of RAM" in err
    assert "--schedule min-buffer" in err and "dataflow 'Convert'" in err
    assert "largest in RAM: el_df0_" in err
    assert not (tmp_path / "c" / "cd_to_dat.elf").exists()


def test_cd_to_dat_fits_the_atmega328p_with_min_buffer_schedules(tmp_path):
    built = avr_build(ROOT / "examples/cd_to_dat.elab", tmp_path / "c", "--release", "--schedule", "min-buffer")
    s = sizes(built)
    assert s["mcu"] == "atmega328p" and s["ram"] + 256 <= 2048 and s["flash"] < s["flash_max"]
    # The long min-buffer schedule is a table walked by a loop, not 613
    # firings of straight-line code.
    assert "el_seq[" in (tmp_path / "c" / "model.c").read_text()


def test_a_debug_build_that_does_not_fit_points_at_release_builds(tmp_path):
    # With its own schedule: the min-buffer debug build fits the 328P (tests/avr/test_avr_footprint.py).
    built = avr_build(ROOT / "examples/cd_to_dat.elab", tmp_path / "c", ok=False)
    assert "a --release build has none" in built.proc.stderr
    assert "or build for --mcu atmega2560" in built.proc.stderr


def test_pt100_sensor_on_the_atmega328p_names_the_missing_second_uart(tmp_path):
    built = avr_build(ROOT / "examples/pt100_sensor.elab", tmp_path / "p", ok=False)
    err = built.proc.stderr
    assert re.search(r"examples/pt100_sensor\.elab:\d+: error: interface 'modbus rtu' claims uart\[1\], but the "
                     r"atmega328p has no UART 1 \(it has uart0 only\)", err), err
    assert "PB7 is XTAL2" in err  # its alarm LED sits on a crystal pin of the Uno
    assert err.startswith("easylab: error: the model does not fit the avr board with the atmega328p (2 problems)")


# ---------------------------------------------------------------- claims and drivers

CLASH = """device led: DigitalOut(pin = "PB5")
device valve: PwmOut(pin = "PB5")
param duty: int16 = 10
dataflow D {
    c = Const<int16>(value = duty)
    w = SquareWave(half_period = 5)
    c.y -> valve.duty
    w.y -> led.level
}
task t period 10 ms { run D }
"""


def test_one_pin_through_two_resources_is_refused_naming_both_owners(tmp_path):
    model = write_model(tmp_path, "clash", CLASH)
    err = avr_build(model, tmp_path / "o", "--mcu", "atmega2560", ok=False).proc.stderr
    assert (f"{model}:5: error: pin PB5 is claimed twice on the atmega2560: as pwm[\"PB5\"] by device 'valve' "
            f"and as pin[\"PB5\"] by device 'led' ({model}:4)") in err


@pytest.mark.parametrize("body, mcu, message", [
    # PWM on a pin without a timer channel
    ('device v: PwmOut(pin = "PB0")\nparam d: int16 = 1\ndataflow D { c = Const<int16>(value = d)  c.y -> v.duty }\n'
     'task t period 10 ms { run D }\n', "atmega2560",
     "claims pwm[\"PB0\"], but PB0 has no timer output; PWM pins of the atmega2560:"),
    # the tick timer's compare output
    ('device v: PwmOut(pin = "PB4")\nparam d: int16 = 1\ndataflow D { c = Const<int16>(value = d)  c.y -> v.duty }\n'
     'task t period 10 ms { run D }\n', "atmega2560",
     "PB4's timer output (OC2A) belongs to Timer2, which runs the LET tick"),
    # an ADC channel the part lacks
    ('device a: AnalogIn(channel = 8)\nvar x: uint16\ndataflow D { a.value -> x }\ntask t period 10 ms { run D }\n',
     "atmega328p", "claims adc[8], but the atmega328p has no ADC channel 8 (channels 0..7)"),
    # an ADC pin used as a digital pin
    ('device a: AnalogIn(channel = 0)\ndevice b: DigitalIn(pin = "PF0")\nvar x: uint16\nvar y: bool\n'
     'dataflow D { a.value -> x  b.level -> y }\ntask t period 10 ms { run D }\n', "atmega2560",
     "pin PF0 is claimed twice on the atmega2560: as pin[\"PF0\"] by device 'b' and as adc[0] by device 'a'"),
    # a UART's pin used as a digital pin (USART1 is PD2/PD3 on the 2560)
    ('device b: DigitalIn(pin = "PD3")\nvar y: bool\ndataflow D { b.level -> y }\ntask t period 10 ms { run D }\n'
     'modbus rtu on uart1\n', "atmega2560",
     "pin PD3 is claimed twice on the atmega2560: as uart[1] by interface 'modbus rtu' and as pin[\"PD3\"]"),
    # a resource kind the board does not have
    ('device type Can() {\n    claims can[0]\n    out v: uint8\n    driver "can_dev"\n}\ndevice s: Can()\nvar x: uint8\n'
     'dataflow D { s.v -> x }\ntask t period 10 ms { run D }\n', "atmega2560",
     "claims can[0], but the avr board has no resource kind 'can' (kinds: pin, pwm, adc, uart, i2c, spi)"),
    # Modbus TCP
    ('var x: uint8 service ro\nmodbus tcp port 1502\n', "atmega2560",
     "the Modbus TCP interface needs a network, and the avr board has none"),
    # an encoder on pins without interrupts
    ('device e: Encoder(pin_a = "PA0", pin_b = "PA1")\nvar x: int32\ndataflow D { e.count -> x }\n'
     'task t period 10 ms { run D }\n', "atmega2560",
     "needs an interrupt on PA0, which has neither a pin-change nor an external interrupt on the atmega2560"),
])
def test_resources_the_part_lacks_are_refused_with_the_claim_and_its_line(tmp_path, body, mcu, message):
    model = write_model(tmp_path, "bad", body)
    err = avr_build(model, tmp_path / "o", "--mcu", mcu, ok=False).proc.stderr
    assert message in err, err
    assert re.search(rf"{re.escape(str(model))}:\d+: error: ", err), err


def test_a_device_without_an_avr_driver_names_device_driver_and_board(tmp_path):
    model = write_model(tmp_path, "lidar", """device type Lidar() {
    claims uart[1]
    out range: uint16
    driver "lidar"
}
device scanner: Lidar()
var r: uint16
dataflow D { scanner.range -> r }
task t period 10 ms { run D }
""")
    err = avr_build(model, tmp_path / "o", "--mcu", "atmega2560", ok=False).proc.stderr
    assert f"{model}:9: error: device 'scanner' needs the driver 'lidar', which the avr board does not have" in err


def test_line_follower_builds_with_the_line_camera_driver(sim_builds):
    built = sim_builds["line_follower"]
    devices = (built.elf.parent / "el_avr_devices.h").read_text()
    assert "static const el_drv_line_camera_t el_dev6 = { 2u," in devices  # uart2


def test_unknown_mcu_and_options_of_other_boards(tmp_path):
    proc = cli("build", ROOT / "examples/blink.elab", "--board", "avr", "--mcu", "atmega8", "-o", tmp_path / "x")
    assert proc.returncode == 1 and "board 'avr' has no MCU 'atmega8' (MCUs: atmega2560, atmega328p)" in proc.stderr
    proc = cli("build", ROOT / "examples/blink.elab", "--board", "host", "--mcu", "atmega2560", "-o", tmp_path / "y")
    assert proc.returncode == 1 and "board 'host' has no MCU choice (--mcu)" in proc.stderr


def test_generated_device_code_folds_to_single_instructions(tmp_path):
    """blink's LED: the DigitalOut driver's write reduces to SBI/CBI on PORTB."""
    built = avr_build(ROOT / "examples/blink.elab", tmp_path / "b", "--release")
    dis = subprocess.run(["avr-objdump", "-d", str(built.elf)], capture_output=True, text=True, check=True).stdout
    publish = dis.split("<el_gen_publish>:")[1].split("\n\n")[0]
    assert "sbi\t0x05, 5" in publish and "cbi\t0x05, 5" in publish


# ---------------------------------------------------------------- the tick


@pytest.mark.parametrize("tick_us", [1000, 5000, 10000, 20000, 250, 100, 1500, 7000, 100000, 1000000])
def test_the_tick_timer_divides_common_ticks_exactly(tick_us):
    from easylab.board.registry import board_module
    tick_timer = board_module("avr", "devices").tick_timer

    t = tick_timer(tick_us, 16_000_000)
    assert t.exact and t.prescale * (t.ocr + 1) * t.isrs == tick_us * 16
    assert 1 <= t.ocr <= 255 and 1 <= t.isrs <= 65535
    assert t.isr_cycles <= 16000 or t.isrs == 1  # at most 1 ms between interrupts
    assert t.isr_cycles >= 800  # at least 50 us


def test_a_tick_no_setting_divides_drifts_by_a_stated_amount():
    from easylab.board.registry import board_module
    tick_timer = board_module("avr", "devices").tick_timer

    t = tick_timer(65537 * 3, 16_000_000)  # 3 x a prime number of us
    assert not t.exact and abs(t.drift_ppm) < 100


# ---------------------------------------------------------------- make


def test_make_flash_shows_the_avrdude_command():
    proc = subprocess.run(["make", "-n", "flash", "BOARD=avr", "MODEL=examples/pt100_sensor.elab",
                           "PORT=/dev/ttyACM0", "MCU=atmega2560"], cwd=ROOT, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert ("avrdude -p m2560 -c wiring -P /dev/ttyACM0 -b 115200 -D "
            "-U flash:w:build/flash/pt100_sensor-atmega2560/pt100_sensor.hex:i") in proc.stdout
    assert ("build examples/pt100_sensor.elab --board avr --mcu atmega2560 "
            "-o build/flash/pt100_sensor-atmega2560") in proc.stdout
    proc = subprocess.run(["make", "-n", "flash", "BOARD=avr", "MODEL=examples/blink.elab", "PORT=/dev/ttyUSB0"],
                          cwd=ROOT, capture_output=True, text=True)
    assert "avrdude -p m328p -c arduino -P /dev/ttyUSB0 -b 115200 -D" in proc.stdout


def test_make_flash_needs_a_port():
    proc = subprocess.run(["make", "-n", "flash", "BOARD=avr", "MODEL=examples/blink.elab"], cwd=ROOT,
                          capture_output=True, text=True)
    assert proc.returncode != 0 and "PORT=" in proc.stdout + proc.stderr


def test_make_sim_runs_the_harness():
    proc = subprocess.run(["make", "-n", "sim", "BOARD=avr", "MODEL=examples/blink.elab"], cwd=ROOT,
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert "--board avr --mcu atmega328p --sim" in proc.stdout
    assert "build/sim/blink-atmega328p/blink-sim --uart0 pty:build/sim/blink-atmega328p/uart0" in proc.stdout


# ---------------------------------------------------------------- options per file


def test_options_per_file_reach_only_their_runtime_or_port_file(tmp_path):
    """board.toml's [toolchain.file_cflags]: after the common flags, for the
    named runtime or port file only; a generated file of the same name
    gets none. The AVR board names el_debug.c there."""
    from easylab.board.cbuild import compile_objects
    from easylab.board.description import read_description

    chain = read_description(ROOT / "boards" / "avr").toolchain
    assert chain.file_cflags["el_debug.c"] and "file_cflags" not in chain.tools
    port, generated = tmp_path / "port", tmp_path / "gen"
    port.mkdir(), generated.mkdir()
    check = "#if MARK != {}\n#error MARK\n#endif\nint {};\n"
    (port / "marked.c").write_text(check.format(2, "marked"))
    (port / "other.c").write_text(check.format(1, "other"))
    (generated / "marked.c").write_text(check.format(1, "marked_gen"))
    objects = compile_objects(chain.cc, ["-mmcu=atmega328p", "-Os", "-Werror", "-DMARK=1"],
                              [port / "marked.c", port / "other.c", generated / "marked.c"], tmp_path / "obj",
                              generated, {"marked.c": ["-UMARK", "-DMARK=2"]})
    assert [o.name for o in objects] == ["marked.o", "other.o", "marked_gen.o"]
