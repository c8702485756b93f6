"""The PIC18 board's builds: sizes against the part and the builds that do
not fit, the claims and the part's own rules with their messages, the
toolchain's absence, the tick timer, the compiler keywords behind the
board's header, the make targets."""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest

from pic18_testlib import ROOT, cli, pic18_build, run, sizes, write_model

BOARD = ROOT / "boards" / "pic18"


# ---------------------------------------------------------------- sizes

def test_blink_in_release_fits_the_pic18f4520(build_cache):
    built = build_cache.get(("pic18-blink-release",),
                            lambda out: pic18_build(ROOT / "examples" / "blink.elab", out, "--release"))
    s = sizes(built)
    assert s["mcu"] == "pic18f4520" and s["flash_max"] == 32768 and s["ram_max"] == 1536
    assert 0 < s["flash"] < s["flash_max"] and 384 < s["ram"] < s["ram_max"]  # the RAM counts the 384-byte stack
    assert built.lines[-2].startswith("pic18f4520: program memory") and built.lines[-1] == str(built.elf)
    records = [line for line in built.elf.read_text().splitlines() if line.startswith(":")]
    assert records[-1] == ":00000001FF"
    assert built.elf.with_suffix(".cod").is_file()  # gpsim's symbolic image


def test_a_debug_build_fits_the_pic18f4620(blink_4620, build_cache):
    debug = sizes(blink_4620)
    release = sizes(build_cache.get(("pic18-blink-release",),
                                    lambda out: pic18_build(ROOT / "examples" / "blink.elab", out, "--release")))
    assert debug["mcu"] == "pic18f4620" and debug["flash_max"] == 65536 and debug["ram_max"] == 3968
    assert debug["flash"] < debug["flash_max"] and debug["ram"] < debug["ram_max"]
    assert debug["flash"] > release["flash"] + 8000  # the debug server (about 9.4 KB)


def test_blinks_debug_build_fits_the_pic18f4520_with_buffers_sized_from_the_model(tmp_path):
    """The PIC18F4520's 1.5 KB of RAM: the debug server's frame, queues and
    breakpoint slots and the debug EUSART's receive ring are sized from the
    model (docs/protocol.md), as on the ATmega328P; the PIC18F4620 keeps
    the protocol's largest. Responses go out from the server's buffer: no
    transmit ring."""
    built = pic18_build(ROOT / "examples" / "blink.elab", tmp_path / "b")
    s = sizes(built)
    assert s["mcu"] == "pic18f4520" and s["flash"] <= 32768 and s["ram"] <= 1536, s
    assert "#define EL_DBG_FRAME 30u" in (tmp_path / "b" / "el_debug_config.h").read_text()
    config = (tmp_path / "b" / "el_pic18_config.h").read_text()
    assert "#define EL_PIC18_UART_RX (EL_DBG_FRAME + 3u)" in config  # a request; no transmit ring
    assert "#define EL_PIC18_UART_TX 0u" in config
    pic18_build(ROOT / "examples" / "blink.elab", tmp_path / "big", "--mcu", "pic18f4620")
    assert "#define EL_PIC18_UART_RX (EL_DBG_MAX_FRAME + 3u)" in (tmp_path / "big" / "el_pic18_config.h").read_text()


def test_a_debug_build_too_big_for_the_pic18f4520_says_by_how_much(tmp_path):
    from firmware_builds import board_model

    model = board_model("pic18", ROOT / "examples" / "pneumatic_cylinder.elab", "debug", tmp_path / "model")
    built = pic18_build(model, tmp_path / "b", ok=False)
    err = built.proc.stderr
    m = re.search(r"pic18f4520: program memory (\d+) of 32768 bytes, RAM (\d+) of 1536 bytes", err)
    assert m, err
    flash = int(m.group(1))
    assert flash > 32768, err
    assert (f"error: the program does not fit the pic18f4520's 32768 bytes of program memory "
            f"({flash - 32768} bytes too many)") in err
    assert "a --release build has none" in err and "or build for --mcu pic18f4620" in err
    assert not (tmp_path / "b" / "pneumatic_cylinder.hex").exists()


def test_a_program_too_big_with_persist_params_says_what_persist_costs(tmp_path):
    """pneumatic_cylinder's debug build for the PIC18F4520 overflows its
    program memory; its three persist params cost board.toml's
    persist_program_bytes, and without them it would fit."""
    import tomllib

    from firmware_builds import board_model

    cost = tomllib.loads((BOARD / "board.toml").read_text(encoding="utf-8"))["persist_program_bytes"]
    model = board_model("pic18", ROOT / "examples" / "pneumatic_cylinder.elab", "debug", tmp_path / "model")
    err = pic18_build(model, tmp_path / "b", ok=False).proc.stderr
    flash = int(re.search(r"pic18f4520: program memory (\d+) of 32768 bytes", err).group(1))
    assert flash - cost <= 32768 < flash, err
    assert (f"; its 3 persist params (target, kp, ki) cost about {cost / 1024:.1f} KB of program memory on the "
            f"pic18f4520 ({cost} bytes: the EEPROM records, their checks and the service layer they are written "
            f"through; without persist the program would fit): drop persist from the params that need not "
            f"survive a reset; or build for --mcu pic18f4620") in err, err
    m = re.search(r'^gplink: error: No target memory available for section "(\S+)"\.$', err, re.M)
    assert m, err
    assert re.search(rf'^section "{re.escape(m.group(1))}": program memory, \d+ bytes, \w+ in \w+\.c$', err, re.M), err


def test_what_persist_costs_on_the_pic18f4520_is_measured(tmp_path):
    """board.toml's persist_program_bytes against two release builds of the
    board's pneumatic_cylinder for the PIC18F4520, with and without its
    persist params (within 3 %: the runtime may move a little)."""
    import tomllib

    cost = tomllib.loads((BOARD / "board.toml").read_text(encoding="utf-8"))["persist_program_bytes"]
    text = (BOARD / "conformance" / "pneumatic_cylinder.elab").read_text(encoding="utf-8")
    assert text.count(" persist") == 3
    flash = {}
    for name, body in (("with", text), ("without", text.replace(" persist", ""))):
        (tmp_path / name).mkdir()
        model = tmp_path / name / "pneumatic_cylinder.elab"
        model.write_text(body, encoding="utf-8")
        flash[name] = sizes(pic18_build(model, tmp_path / name / "b", "--release"))["flash"]
    assert abs(flash["with"] - flash["without"] - cost) <= 0.03 * cost, (flash, cost)


def test_a_program_too_big_for_the_ram_names_the_largest_objects(tmp_path):
    """Objects larger than a 256-byte bank sit between the banks and the
    stack (sdcc_quirks.place_big_objects): too many are refused before
    anything is compiled, naming them."""
    model = write_model(tmp_path, "big", "var a: int16\nchannel c: int16 delay 300\n"
                                         "dataflow P { s = Const<int16>(value = 1)  s.y -> c }\n"
                                         "dataflow Q { w = WindowStats<int16>(n = 300)  c -> w.x  w.max -> a }\n"
                                         "task p period 1 ms { run P }\ntask q period 300 ms { run Q }\n")
    err = pic18_build(model, tmp_path / "b", "--release", ok=False).proc.stderr
    assert ("the program does not fit the pic18f4520's 1536 bytes of RAM: the RAM objects larger than a bank "
            "take 1804 bytes, more than the 1023 bytes of RAM between the access bank and the stack: el_t1 604 B, "
            "el_ch0_ring 600 B, el_df1_b0 600 B; dataflow buffers shrink with --schedule min-buffer; or build for "
            "--mcu pic18f4620") in err, err


def test_a_section_gplink_cannot_place_is_named_with_gplinks_message_and_its_size(tmp_path):
    """An actor's initialised local array of 300 bytes: sdcc gives it a RAM
    section of its own, and no 256-byte bank holds it. The error quotes
    gplink, names the section, its memory, size and symbol, and guesses
    nothing about program memory or the debug server."""
    model = write_model(tmp_path, "table", "actor type Lookup<T: integer>(k: T = 1) {\n    in  x: T\n    out y: T\n"
                                           "    step {{ uint8_t t[300] = {1, 2, 3}; y = (T)(k * t[(uint16_t)x % 300u]); }}\n"
                                           "}\nvar v: uint8\n"
                                           + LOOP % "s = Const<uint8>(value = 7)  a = Lookup<uint8>()  s.y -> a.x  a.y -> v")
    err = pic18_build(model, tmp_path / "b", "--mcu", "pic18f4620", ok=False).proc.stderr
    assert err.startswith("easylab: error: the program does not fit the pic18f4620's RAM banks: gplink could not "
                          "place a 300-byte RAM section, and a RAM section must fit within one 256-byte bank"), err
    assert "a table that is only read can be 'static const' (program memory)" in err, err
    m = re.search(r'^gplink: error: No target memory available for section "(\w+)"\.$', err, re.M)
    assert m, err
    assert re.search(rf'^section "{m.group(1)}": RAM, 300 bytes, el_df0_D_t_\w+ in model\.c$', err, re.M), err
    assert "debug server" not in err and "program memory of" not in err, err
    assert not (tmp_path / "b" / "table.hex").exists()


def test_cd_to_dat_with_the_min_buffer_schedule_gives_the_host_trace_on_the_pic18f4620(tmp_path):
    """The min-buffer schedule copies the checksum's 160 tokens out of their
    ring into a local array of 640 bytes, larger than a bank: it is placed
    with the other big objects (sdcc_quirks), the build fits the PIC18F4620
    (debug too) and runs as the host board's."""
    from firmware_builds import build

    model = ROOT / "examples" / "cd_to_dat.elab"
    debug = sizes(pic18_build(model, tmp_path / "d", "--mcu", "pic18f4620", "--schedule", "min-buffer"))
    assert debug["flash"] <= 65536 and debug["ram"] <= 3968, debug
    pic = pic18_build(model, tmp_path / "p", "--mcu", "pic18f4620", "--schedule", "min-buffer", "--sim", "--release")
    assert "el_in_x__el_df0_" in (tmp_path / "p" / "obj" / "model_gen.sdcc.c").read_text()
    host = build(model, "host", tmp_path / "h", "--schedule", "min-buffer")
    args = ["--fast", "--duration", "2s"]
    run(host.executable, *args, "--trace", tmp_path / "host.csv")
    assert run(pic.simulator, *args, "--trace", tmp_path / "pic18.csv").stderr == ""
    host_trace = (tmp_path / "host.csv").read_text()
    assert (tmp_path / "pic18.csv").read_text() == host_trace and host_trace.count("\n") == 101


def test_pt100_sensor_on_the_pic18f4520_names_the_missing_second_uart(tmp_path):
    err = pic18_build(ROOT / "examples" / "pt100_sensor.elab", tmp_path / "p", ok=False).proc.stderr
    assert re.search(r"examples/pt100_sensor\.elab:\d+: error: interface 'modbus rtu' claims uart\[1\], but the "
                     r"pic18f4520 has no UART 1 \(it has uart0 only\)", err), err
    assert err.startswith("easylab: error: the model does not fit the pic18 board with the pic18f4520"), err


# ---------------------------------------------------------------- claims and the part's rules

LOOP = "dataflow D { %s }\ntask t period 10 ms { run D }\n"


@pytest.mark.parametrize("body, message", [
    # PWM on a pin without a CCP module (CCP2 is on RC1: CCP2MX = PORTC)
    ('device v: PwmOut(pin = "RB3")\nparam d: int16 = 1\n' + LOOP % "c = Const<int16>(value = d)  c.y -> v.duty",
     "claims pwm[\"RB3\"], but RB3 has no CCP output; PWM pins of the pic18f4520: RC1, RC2"),
    # one pin through two resources
    ('device led: DigitalOut(pin = "RC2")\ndevice valve: PwmOut(pin = "RC2")\nparam d: int16 = 1\n'
     + LOOP % "c = Const<int16>(value = d)  w = SquareWave(half_period = 5)  c.y -> valve.duty  w.y -> led.level",
     "pin RC2 is claimed twice on the pic18f4520: as pwm[\"RC2\"] by device 'valve' and as pin[\"RC2\"] by "
     "device 'led'"),
    # a UART's pin as a digital input
    ('device b: DigitalIn(pin = "RC7")\nvar y: bool\n' + LOOP % "b.level -> y" + "debug on uart0 baud 115200\n",
     "pin RC7 is claimed twice on the pic18f4520: as uart[0] by interface 'debug' and as pin[\"RC7\"]"),
    # the port-and-bit alias names the same pin
    ('device a: DigitalOut(pin = "PB5")\ndevice b: DigitalIn(pin = "RB5")\nvar y: bool\n'
     + LOOP % "b.level -> y  b.level -> a.level",
     "pin RB5 is claimed twice on the pic18f4520"),
    # an ADC channel the part lacks
    ('device a: AnalogIn(channel = 13)\nvar x: uint16\n' + LOOP % "a.value -> x",
     "claims adc[13], but the pic18f4520 has no ADC channel 13 (channels 0..12)"),
    # ADCON1: adc[3] makes AN0..AN3 analog, RA1 (AN1) is no digital input then
    ('device a: AnalogIn(channel = 3)\ndevice b: DigitalIn(pin = "RA1")\nvar x: uint16\nvar y: bool\n'
     + LOOP % "a.value -> x  b.level -> y",
     "device 'b' reads RA1 as a digital input, but on the pic18f4520 adc[3] (device 'a') makes AN0..AN3 analog "
     "together (ADCON1) and RA1 is AN1, which then reads 0"),
    # a second UART
    ('var x: uint8 service ro\nmodbus rtu on uart1 baud 19200\n',
     "interface 'modbus rtu' claims uart[1], but the pic18f4520 has no UART 1 (it has uart0 only)"),
    # Modbus TCP
    ('var x: uint8 service ro\nmodbus tcp port 1502\n',
     "the Modbus TCP interface needs a network, and the pic18 board has none"),
    # an encoder on pins without interrupts
    ('device e: Encoder(pin_a = "RD0", pin_b = "RB3")\nvar x: int32\n' + LOOP % "e.count -> x",
     "device 'e' (encoder) needs an interrupt on RD0, which has neither an external interrupt (INT0..INT2 on "
     "RB0..RB2) nor PORTB's interrupt on change (RB4..RB7) on the pic18f4520; pins that can: RB0..RB2, RB4..RB7"),
    # a crystal pin
    ('device l: DigitalOut(pin = "RA6")\nparam p: int16 = 1\n'
     + LOOP % "c = Const<int16>(value = p)  k = Compare<int16>(op = \">\", threshold = 0)  c.y -> k.x  k.y -> l.level",
     "the pic18f4520's RA6 is OSC2 (the 10 MHz crystal)"),
])
def test_resources_the_part_lacks_are_refused_with_the_claim_and_its_line(tmp_path, body, message):
    model = write_model(tmp_path, "bad", body)
    err = pic18_build(model, tmp_path / "o", ok=False).proc.stderr
    assert message in err, err
    assert re.search(rf"{re.escape(str(model))}:\d+: error: ", err), err


def test_the_boards_problems_are_reported_sorted_by_position(tmp_path):
    """docs/language.md: every error of a run is sorted by position. The
    claims are checked devices first, then interfaces, then the part's own
    rules: an interface declared above two devices with pins the part lacks
    is reported first, and the devices in line order."""
    model = write_model(tmp_path, "order", 'var x: uint8 service ro\nmodbus rtu on uart1 baud 19200\n'
                                           'device b: DigitalOut(pin = "RQ1")\ndevice a: DigitalOut(pin = "RZ9")\n'
                                           + LOOP % "w = SquareWave(half_period = 5)  w.y -> a.level  w.y -> b.level")
    err = pic18_build(model, tmp_path / "o", ok=False).proc.stderr
    assert err.startswith("easylab: error: the model does not fit the pic18 board with the pic18f4520 "
                          "(3 problems):\n"), err
    lines = [int(m.group(1)) for m in re.finditer(rf"^{re.escape(str(model))}:(\d+): error: ", err, re.M)]
    assert lines == [5, 6, 7], err
    assert "uart[1]" in err.splitlines()[1] and "RQ1" in err.splitlines()[2] and "RZ9" in err.splitlines()[3], err


def test_unknown_mcu(tmp_path):
    proc = cli("build", ROOT / "examples/blink.elab", "--board", "pic18", "--mcu", "pic18f452", "-o", tmp_path / "x")
    assert proc.returncode == 1
    assert "board 'pic18' has no MCU 'pic18f452' (MCUs: pic18f4520, pic18f4620)" in proc.stderr


def test_a_missing_toolchain_says_how_to_get_it(tmp_path):
    proc = cli("build", ROOT / "examples/blink.elab", "--board", "pic18", "--release", "-o", tmp_path / "x",
               env={"EASYLAB_PIC18_SDCC": str(tmp_path / "nothing")})
    assert proc.returncode == 1
    assert (f"the pic18 board's compiler (sdcc with its pic16 port) is not built in {tmp_path / 'nothing'}"
            in proc.stderr)
    assert "`make setup` builds it" in proc.stderr and "boards/pic18/toolchain/build.sh" in proc.stderr
    assert "EASYLAB_PIC18_SDCC names another folder" in proc.stderr


def test_a_stack_that_runs_out_stops_the_simulation(tmp_path):
    """The harness's guard at the bottom of sdcc's software stack: the board
    with a 64-byte stack (a copy of boards/pic18 whose board.toml says so,
    found first through --board-path) runs blink into it."""
    board = tmp_path / "boards" / "pic18"
    shutil.copytree(BOARD, board, ignore=shutil.ignore_patterns("__pycache__"))
    toml = board / "board.toml"
    toml.write_text(toml.read_text().replace("stack = 384", "stack = 64"))
    built = pic18_build(ROOT / "examples" / "blink.elab", tmp_path / "b", "--release", "--sim", "--board-path",
                        tmp_path / "boards")
    assert "64-byte stack" in built.proc.stdout
    proc = run(built.simulator, "--fast", "--duration", "100ms", ok=False)
    assert proc.returncode == 1
    assert "the pic18f4520's software stack (64 bytes, board.toml's stack) ran out at cycle" in proc.stderr


# ---------------------------------------------------------------- the tick

@pytest.mark.parametrize("tick_us", [100, 250, 500, 1000, 1500, 5000, 10000, 20000, 100000, 1000000])
def test_the_tick_timer_divides_common_ticks_exactly(tick_us):
    from easylab.board.registry import board_module
    tick_timer = board_module("pic18", "devices").tick_timer

    t = tick_timer(tick_us, 10_000_000)
    assert t.exact and t.drift_ppm == 0
    assert t.prescale * (t.pr2 + 1) * t.postscale * t.isrs == tick_us * 10
    assert 500 <= t.prescale * (t.pr2 + 1) * t.postscale <= 10000  # interrupts 50 us .. 1 ms apart
    if tick_us % 100 == 0:
        assert t.prescale * (t.pr2 + 1) == 1000  # the PWM's period: 10 kHz with 10-bit duty


def test_a_tick_no_setting_divides_drifts_by_a_stated_amount():
    from easylab.board.registry import board_module
    tick_timer = board_module("pic18", "devices").tick_timer

    t = tick_timer(4093, 10_000_000)  # a prime number of us
    assert not t.exact and abs(t.drift_ppm - 24.4) < 0.1


# ---------------------------------------------------------------- the sources

SDCC_KEYWORDS = re.compile(r"__(interrupt|at|sfr|sbit|asm|endasm|naked|code|data|critical|wparam|reentrant|shadowregs)"
                           r"\b")


def test_compiler_keywords_stay_behind_the_boards_header():
    """Only el_pic18.h (and the sdcc-only start-up file) name sdcc's
    keywords: MPLAB XC8 needs the header's other branch only."""
    sources = sorted(BOARD.glob("*.[ch]")) + sorted((BOARD / "drivers").glob("*.h"))
    offenders = {p.name: m.group(0) for p in sources if p.name not in ("el_pic18.h", "pic18_startup.c")
                 for m in [SDCC_KEYWORDS.search(re.sub(r"/\*.*?\*/", "", p.read_text(), flags=re.S))] if m}
    assert offenders == {}
    assert "__XC8" in (BOARD / "el_pic18.h").read_text()


# ---------------------------------------------------------------- make

def test_make_flash_shows_the_programmers_command():
    proc = subprocess.run(["make", "-n", "flash", "BOARD=pic18", "MODEL=examples/blink.elab", "PORT=usb",
                           "BUILD_FLAGS=--release"], cwd=ROOT, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert "build examples/blink.elab --board pic18 --mcu pic18f4520 -o build/flash/blink-pic18f4520" in proc.stdout
    assert "ipecmd.sh -TPPK3 -PPIC18F4520 -Fbuild/flash/blink-pic18f4520/blink.hex -M -OL" in proc.stdout


def test_make_sim_runs_the_harness():
    proc = subprocess.run(["make", "-n", "sim", "BOARD=pic18", "MODEL=examples/blink.elab", "MCU=pic18f4620"],
                          cwd=ROOT, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert "--board pic18 --mcu pic18f4620 --sim" in proc.stdout
    assert ("build/sim/blink-pic18f4620/blink-sim --uart0 pty:build/sim/blink-pic18f4620/uart0"
            in proc.stdout)
