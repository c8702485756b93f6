"""The f16 board's builds for the part (docs/boards.md, "The F16 board"): a
Softune project that builds on its own, the proxies' checks over every file
of it, the part's resources, and what the board refuses.

The conformance suite (tests/boards) covers what every board shares: the
port contract program and the examples' traces on the 16-bit proxy, claims
the part lacks, sizes, release builds."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from firmware_builds import ROOT, build, cli

HERE = Path(__file__).resolve().parent
DEMO = HERE / "models" / "f16_demo.elab"


@pytest.fixture(scope="module")
def demo(build_cache):
    """f16_demo for the part, with every proxy check (--check)."""
    return build_cache.get(("f16", "f16_demo", "--check"),
                           lambda out: (build(DEMO, "f16", out, "--check"), out))


def test_a_build_is_a_softune_project_that_needs_only_softune(demo):
    built, out = demo
    makefile = (out / "Makefile").read_text()
    assert re.search(r"^CC = \$\(SOFTUNE\)/BIN/fcc907s$", makefile, re.M)
    assert re.search(r"^LD = \$\(SOFTUNE\)/BIN/flnk907s$", makefile, re.M)
    assert "CFLAGS = -cpu $(CPU) -model MEDIUM -O 4 -B -w 5 -D EL_BOARD_STDINT -D EL_F16_FCC907S -D EL_DEBUG=1" \
        in makefile
    assert "-ra _INRAM01=0x000100/0x0018FF" in makefile and "-ro _INROM01=0xFE0000/0xFFFFFF" in makefile
    # Every source the Makefile compiles is in the folder: it builds elsewhere.
    compiled = re.findall(r"^obj/\w+\.obj: (\S+) \| obj$", makefile, re.M)
    assert "model.c" in compiled and "runtime/el_dispatch.c" in compiled and "board/f16_port.c" in compiled
    assert all((out / src).is_file() for src in compiled if src != "start.asm")
    assert (out / "board" / "mb90f543_regs.h").is_file() and (out / "runtime" / "el_wide.h").is_file()
    # The compiler's keywords and pragmas stand behind macros and EL_F16_FCC907S only.
    vectors = (out / "el_f16_vectors.c").read_text()
    assert re.search(r"#if defined\(EL_F16_FCC907S\)\n#pragma section INTVECT[^\n]*\n#pragma intvect _start 8 0",
                     vectors)
    assert "#pragma intvect el_f16_tick_interrupt 17" in vectors
    assert "#pragma intvect el_f16_int_15_interrupt 15" in vectors  # the encoder on INT0/INT1
    for path in sorted(out.glob("*.c")) + sorted((out / "board").glob("*.[ch]")):
        if path.name == "f16_compiler.h":
            continue
        text = re.sub(r"#if defined\(EL_F16_FCC907S\).*?#endif|/\*.*?\*/", "", path.read_text(), flags=re.S)
        assert not re.search(r"__interrupt|__io\b|__far\b|__DI\(|__EI\(|#pragma", text), path
    # It says that compiling needs Softune, and how.
    lines = built.lines
    assert any(line.startswith("compiling for the mb90f543 needs Softune (fcc907s, flnk907s), which does not run "
                               "here") and f"make -C {out} SOFTUNE=C:/Softune" in line
               and "fcc907s -cpu MB90F543 -model MEDIUM" in line for line in lines), lines
    assert lines[-1] == str(out)


def test_every_file_passes_the_proxies(demo):
    built, out = demo
    # Every C file of the project (out/, its runtime/ and board/) goes through both.
    files = len([p for p in out.rglob("*.c")])
    assert f"proxy: gcc -std=c89 -pedantic-errors -Wall -Wextra -Werror: {files} files clean" in built.lines
    assert f"proxy: clang --target=msp430 -std=c89 -pedantic-errors -Wall -Wextra -Werror: {files} files clean" \
        in built.lines
    assert any(line.startswith("proxy: clang-tidy bugprone-implicit-widening-of-multiplication-result, "
                               "bugprone-narrowing-conversions") for line in built.lines)
    assert re.search(r"^mb90f543: flash about \d+ of 131072 bytes, RAM about \d+ of 6144 bytes", built.size_line)


def test_the_tick_and_uart_come_from_the_parts_timers(demo):
    _, out = demo
    config = (out / "el_f16_config.h").read_text()
    # 1 ms = 8000 counts of 16 MHz / 2: exact, one interrupt per tick.
    assert "#define EL_F16_TICK_RELOAD 7999u" in config and "#define EL_F16_TICK_ISRS 1u" in config
    assert "(exact)" in config
    # 38400 baud: 16 MHz / 1 / (208 << 1) = 38462 baud.
    assert "#define EL_F16_UART1_DIV 1u" in config and "#define EL_F16_UART1_CS 1u" in config
    hw = (out / "hw_map.json").read_text()
    assert '"pin_a": "P60"' in hw and '"int": [\n        0,\n        1\n      ]' in hw


def test_a_release_build_leaves_the_debug_server_out_of_the_project(tmp_path):
    built = build(DEMO, "f16", tmp_path / "r", "--release")
    makefile = (tmp_path / "r" / "Makefile").read_text()
    assert "-D EL_RELEASE=1" in makefile and "el_debug" not in makefile
    assert not list((tmp_path / "r" / "runtime").glob("el_debug*.c"))
    assert "el_f16_uart1" not in (tmp_path / "r" / "el_f16_vectors.c").read_text()  # debug was its only user
    assert built.lines[-1] == str(tmp_path / "r")


BAD = """model bad
import std
device led: DigitalOut(pin = "P20")
device lamp: PwmOut(pin = "P21")
device wheel: Encoder(pin_a = "P60", pin_b = "P30")
device level: AnalogIn(channel = 9)
param gain: int16 = 10 persist
var x: bool
dataflow D {
    w = SquareWave(half_period = 5)
    c = Const<int16>(value = gain)
    w.y -> led.level
    c.y -> lamp.duty
    wheel.count -> y
    level.value -> z
}
var y: int32
var z: uint16
task t period 10 ms { run D }
debug on uart1 baud 115200
"""


def test_what_the_part_cannot_do_is_refused_at_its_line(tmp_path):
    model = tmp_path / "bad.elab"
    model.write_text(BAD)
    err = build(model, "f16", tmp_path / "out", ok=False).proc.stderr
    assert err.startswith("easylab: error: the model does not fit the f16 board with the mb90f543 (5 problems):"), err
    loc = re.escape(str(model))
    expected = [
        rf"{loc}:4: error: device 'lamp' claims pwm\[\"P21\"\], but P21 has no PPG output; PWM pins of the "
        r"mb90f543: P70, P71",
        rf"{loc}:5: error: device 'wheel' \(encoder\) needs an interrupt on P30, which is no external interrupt "
        r"\(INTn\) on the mb90f543; pins that can: P60..P67",
        rf"{loc}:6: error: device 'level' claims adc\[9\], but the mb90f543 has no ADC channel 9 \(channels 0..7\)",
        rf"{loc}:7: error: param 'gain' is persist, but the mb90f543 has no storage a program can keep it in",
        rf"{loc}:20: error: uart\[1\] \(debug\): 115200 baud is -33.2 % off on UART1 of the mb90f543 \(its nearest "
        r"rate from the 16 MHz machine clock is 76923\); rates within 2 %: 1200, 2400, 4800, 9600, 19200, 38400, "
        r"76800$",
    ]
    for pattern in expected:
        assert re.search(pattern, err, re.M), (pattern, err)


def test_uart0_is_another_circuit(tmp_path):
    model = tmp_path / "u0.elab"
    model.write_text("model u0\nimport std\nvar v: uint8 service ro\nmodbus rtu on uart0 baud 19200\n")
    err = build(model, "f16", tmp_path / "out", ok=False).proc.stderr
    assert f"{model}:4: error: interface 'modbus rtu' claims uart[0]: UART0 of the mb90f543 is another circuit " \
           f"than UART1 (UMC0, USR0, URD0), which the f16 board does not drive; use uart1" in err, err


def test_c99_in_an_actor_is_caught_by_the_c89_front_ends(tmp_path):
    model = tmp_path / "c99.elab"
    model.write_text("model c99\nimport std\nactor type Twice() {\n    in x: int16\n    out y: int16\n"
                     "    step {{ y = x; int16_t twice = (int16_t)(x * 2); y = twice; }}\n}\n"
                     "var v: int16\ndataflow D { c = Const<int16>(value = 3)  t = Twice()  c.y -> t.x  t.y -> v }\n"
                     "task t period 10 ms { run D }\n")
    err = build(model, "f16", tmp_path / "out", ok=False).proc.stderr
    assert re.search(r"model\.c:\d+:\d+: error: mixing declarations and code is a C99 extension", err), err


def test_flashing_is_explained_not_run(tmp_path):
    proc = cli("flash", DEMO, "--board", "f16", "--port", "COM3", "-o", tmp_path)
    assert proc.returncode == 1
    assert "the f16 board is flashed from Windows: build f16_demo.mhx with Softune" in proc.stderr
    assert "FLASH MCU Programmer for the F2MC-16LX (part MB90F543, asynchronous serial mode, on COM3)" in proc.stderr


def test_the_board_is_listed_with_its_part():
    proc = cli("boards")
    assert re.search(r"^f16: Fujitsu F2MC-16LX MB90F543: .*\(MCUs: mb90f543; default mb90f543\)$", proc.stdout, re.M)
    assert (ROOT / "boards" / "f16" / "board.toml").is_file()
