"""The board conformance suite: what makes a folder a board
(docs/boards.md, "Adding a board"). Every test runs on every board found
(the installed ones and a user's board in a temporary folder on
EASYLAB_BOARD_PATH); a new board gets them by existing.

- the port contract program (port_contract.c) on every MCU of the board;
- every example that fits the board gives the host board's trace, value
  by value and instant by instant (boards with a simulator); one that
  board.toml says does not fit ([conformance.does_not_fit]) fails to build
  saying why;
- resource claims the board cannot honour are refused, each naming the
  claim, its owner and its line; so is a device whose type brings handler
  files for other boards only (unless the board simulates devices);
- a build reports its size against the part;
- a release build has none of the debug interface's code.
"""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest

from boards_testlib import (BOARD_PATH, CONTRACT, ENV, USER_BOARD, USER_BOARD_PATH, board_names, conformance,
                            conformance_mcu, conformance_model)
from firmware_builds import EXAMPLE_NAMES, ROOT, build, cli, stimulus_of

BOARDS = board_names()


def load(name: str):
    from easylab.board.registry import load_board

    return load_board(name, BOARD_PATH)


def test_the_boards_found_include_the_installed_ones_and_the_users():
    assert {"host", "avr", USER_BOARD} <= set(BOARDS)
    proc = cli("boards", env=ENV)
    assert proc.returncode == 0, proc.stderr
    assert f"{USER_BOARD} [{USER_BOARD_PATH / USER_BOARD}]" in proc.stdout
    assert re.search(r"^avr: .*\(MCUs: atmega2560, atmega328p; default atmega328p\)$", proc.stdout, re.M)


@pytest.mark.parametrize("board", BOARDS)
def test_the_board_implements_the_contract(board):
    from easylab.board.contract import Board

    b = load(board)
    assert isinstance(b, Board)
    assert b.name == board
    configured = b.configure()
    assert configured.mcu == (b.description.raw.get("default_mcu") or None)


# ---------------------------------------------------------------- the port contract

CHECKS = ["init", "tick_period", "real_tick", "late_tick", "irq_nesting", "irq_masks", "idle", "resync", "nv",
          "instants"]


def parse_report(text: str) -> dict[str, str]:
    results = {}
    for line in text.splitlines():
        if line.startswith("ok "):
            results[line[3:]] = "ok"
        elif line.startswith("FAIL "):
            name, _, detail = line[5:].partition(": ")
            results[name] = detail
    assert text.rstrip().endswith("failed"), text
    return results


def _board_mcus():
    for board in BOARDS:
        for mcu in load(board).mcus() or [None]:
            # A board without MCUs runs its port program natively: its tick,
            # idle and resync checks hold against the wall clock (`realtime`).
            yield pytest.param(board, mcu, id=f"{board}-{mcu}" if mcu else board,
                               marks=[pytest.mark.realtime] if mcu is None else [])


@pytest.mark.parametrize("board, mcu", list(_board_mcus()))
def test_the_port_passes_the_port_contract(board, mcu, tmp_path):
    report = load(board).configure(mcu).run_port_program(CONTRACT, tmp_path)
    assert parse_report(report) == {c: "ok" for c in CHECKS}, report
    assert report.rstrip().endswith("done 0 failed")


# ---------------------------------------------------------------- traces

def _host_trace(build_cache, name: str, tmp_path: Path, duration: str) -> bytes:
    host = build_cache.example("host", name)
    stim = stimulus_of(name)
    trace = tmp_path / "host.csv"
    subprocess.run([str(host.executable), "--fast", "--duration", duration, "--trace", str(trace),
                    *(["--stimulus", str(stim)] if stim else [])], check=True, capture_output=True, timeout=120)
    return trace.read_bytes()


@pytest.mark.parametrize("board", BOARDS)
@pytest.mark.parametrize("name", EXAMPLE_NAMES)
def test_every_example_that_fits_gives_the_host_trace(build_cache, board, name, tmp_path):
    if not load(board).has_simulator:
        pytest.fail(f"board '{board}' has no simulator: its traces are checked by its own suite")
    why = conformance(board).get("does_not_fit", {}).get(name)
    if why is not None:  # the build must fail, saying so and why
        err = build(ROOT / "examples" / f"{name}.elab", board, tmp_path / "b", *conformance_mcu(board), ok=False,
                    env=ENV).proc.stderr
        assert "does not fit" in err and why in err, err
        return
    built = build_cache.example(board, name, *conformance_mcu(board), "--sim", env=ENV)
    assert built.simulator is not None and built.simulator.is_file(), built.proc.stdout
    stim = stimulus_of(name)
    trace = tmp_path / f"{board}.csv"
    proc = subprocess.run([str(built.simulator), "--fast", "--duration", "2s", "--trace", str(trace),
                           *(["--stimulus", str(stim)] if stim else [])], capture_output=True, text=True,
                          timeout=300, stdin=subprocess.DEVNULL)
    assert proc.returncode == 0, proc.stderr
    host = _host_trace(build_cache, name, tmp_path, "2s")
    assert host.count(b"\n") > 3
    assert trace.read_bytes() == host


# ---------------------------------------------------------------- resource claims

BAD_CLAIMS = {
    "a pin the part lacks": ('device d: DigitalOut(pin = "QQ9")\n'
                             'dataflow D { w = SquareWave(half_period = 5)  w.y -> d.level }\n'
                             'task t period 10 ms { run D }\n', r'device \'d\' claims pin\["QQ9"\]'),
    "a UART the part lacks": ('var x: uint8 service ro\nmodbus rtu on uart9\n', r"claims uart\[9\]"),
    "a driver the board lacks": ('device type Lidar() {\n    claims uart[0]\n    out range: uint16\n'
                                 '    driver "no_such_lidar"\n}\ndevice scanner: Lidar()\nvar r: uint16\n'
                                 'dataflow D { scanner.range -> r }\ntask t period 10 ms { run D }\n',
                                 r"device 'scanner' needs the driver 'no_such_lidar', which the \w+ board does not "
                                 r"have"),
}


def _model(tmp_path: Path, body: str) -> Path:
    path = tmp_path / "claims.elab"
    path.write_text(f"model claims\nimport std\n\n{body}", encoding="utf-8")
    return path


@pytest.mark.parametrize("board", BOARDS)
@pytest.mark.parametrize("case", sorted(BAD_CLAIMS))
def test_claims_the_board_cannot_honour_are_refused_at_their_line(board, case, tmp_path):
    body, message = BAD_CLAIMS[case]
    model = _model(tmp_path, body)
    if not conformance(board).get("checks_resources", True):
        build(model, board, tmp_path / "out", env=ENV)  # a board with no pins takes every claim
        return
    err = build(model, board, tmp_path / "out", *conformance_mcu(board), ok=False, env=ENV).proc.stderr
    assert re.search(message, err), err
    assert re.search(rf"{re.escape(str(model))}:\d+: error: ", err), err
    assert err.startswith(f"easylab: error: the model does not fit the {board} board"), err


@pytest.mark.parametrize("board", BOARDS)
def test_a_device_with_handlers_for_other_boards_only_is_refused_saying_what_to_write(board, tmp_path):
    """A device type bringing handler files for other boards (and no
    driver of the board's): refused at its line; a board that simulates
    devices (the host) simulates it instead."""
    (tmp_path / "probe_elsewhere.c").write_text("EL_READ { level = true; }\n")
    model = _model(tmp_path, 'device type Probe() {\n    out level: bool\n'
                             '    driver "no_such_probe" impl no_such_board "probe_elsewhere.c"\n}\n'
                             'device p: Probe()\nvar v: bool\ndataflow D { p.level -> v }\n'
                             'task t period 10 ms { run D }\n')
    if conformance(board).get("simulates_devices"):
        build(model, board, tmp_path / "out", env=ENV)
        return
    err = build(model, board, tmp_path / "out", *conformance_mcu(board), ok=False, env=ENV).proc.stderr
    assert re.search(rf"{re.escape(str(model))}:8: error: device 'p' \(Probe, driver 'no_such_probe'\) has no "
                     rf"handlers for the {board} board: its type brings them for no_such_board only; .* "
                     rf"impl {board} \"FILE\.c\"", err), err


@pytest.mark.parametrize("board", BOARDS)
def test_one_pin_through_two_resources_is_refused_naming_both(board, tmp_path):
    pin = conformance(board).get("pwm_pin")
    if pin is None:
        assert not conformance(board).get("checks_resources", True), \
            f"board '{board}': board.toml's [conformance] names no pwm_pin to test pin sharing with"
        return
    model = _model(tmp_path, f'device led: DigitalOut(pin = "{pin}")\ndevice valve: PwmOut(pin = "{pin}")\n'
                             'param duty: int16 = 10\n'
                             'dataflow D { c = Const<int16>(value = duty)  w = SquareWave(half_period = 5)\n'
                             '    c.y -> valve.duty  w.y -> led.level }\ntask t period 10 ms { run D }\n')
    err = build(model, board, tmp_path / "out", *conformance_mcu(board), ok=False, env=ENV).proc.stderr
    assert f"pin {pin} is claimed twice" in err and "device 'valve'" in err and "device 'led'" in err, err


# ---------------------------------------------------------------- sizes, release builds

def _api_build(board: str, model: Path, out: Path, release: bool):
    from easylab.build import build as do_build
    from easylab.pipeline import lower_file

    program, result = lower_file(model)
    assert program is not None, result.report()
    mcu = conformance(board).get("mcu")
    return do_build(program, board, out, release=release, mcu=mcu, board_path=BOARD_PATH)


@pytest.mark.parametrize("board", BOARDS)
def test_a_build_reports_its_size(board, tmp_path):
    built = _api_build(board, conformance_model(board), tmp_path / "b", release=False)
    size = built.compiled.size
    assert size is not None and size.flash > 0 and size.ram > 0 and size.lines
    if size.flash_max is not None:
        assert size.flash <= size.flash_max and size.ram <= size.ram_max
    proc = cli("build", conformance_model(board), "--board", board, *conformance_mcu(board), "-o",
               tmp_path / "cli", env=ENV)
    assert proc.returncode == 0, proc.stderr
    assert size.lines[0] in proc.stdout.splitlines()


@pytest.mark.parametrize("board", BOARDS)
def test_a_release_build_has_no_debug_code(board, tmp_path):
    debug = _api_build(board, conformance_model(board), tmp_path / "debug", release=False)
    release = _api_build(board, conformance_model(board), tmp_path / "release", release=True)
    debug_symbols = {s for s in debug.board.symbols(debug.compiled) if s.startswith("el_debug_")}
    release_symbols = {s for s in release.board.symbols(release.compiled) if s.startswith("el_debug_")}
    assert "el_debug_poll" in debug_symbols
    assert release_symbols == set()
    assert not any(p.name.startswith("el_debug") for p in release.compiled.sources)


def test_the_users_board_builds_and_runs_an_example(tmp_path):
    built = build(ROOT / "examples/blink.elab", USER_BOARD, tmp_path / "b", env=ENV)
    assert "a board of its own, outside the installation" in built.proc.stdout
    proc = subprocess.run([str(built.executable), "--fast", "--duration", "1s", "--trace", str(tmp_path / "t.csv")],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "t.csv").read_text().count("\n") > 3
    # Without the board path the board is unknown, and the message says which boards there are.
    proc = cli("build", ROOT / "examples/blink.elab", "--board", USER_BOARD, "-o", tmp_path / "c",
               env={"EASYLAB_BOARD_PATH": ""})
    assert proc.returncode == 1 and f"unknown board '{USER_BOARD}' (boards: " in proc.stderr
    # --board-path finds it too.
    proc = cli("build", ROOT / "examples/blink.elab", "--board", USER_BOARD, "--board-path", USER_BOARD_PATH,
               "-o", tmp_path / "d", env={"EASYLAB_BOARD_PATH": ""})
    assert proc.returncode == 0, proc.stderr
