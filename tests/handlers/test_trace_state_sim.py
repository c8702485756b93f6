"""`--trace-state` on every board and in every mode (docs/boards.md,
"Simulation"; docs/language.md, "Device handlers"): the devices' `state`
fields, `DEVICE.FIELD` columns after the items, are traced by the host
firmware, by local execution, by the AVR in simavr and by the PIC18 in
gpsim, byte for byte the same on one stimulus. own_chips/own_state.elab's
humidity sensors count their reads and keep the last four in an array
state, so the state columns move; the simulators read them from the MCU's
RAM at the state's symbol plus each field's offset, which the simulation
build's own compiler checks (device_state.layout_check_lines).
`easylab remote --trace-state` is refused (docs/remote.md)."""

from __future__ import annotations

import random
import shutil
import subprocess
from pathlib import Path
from types import SimpleNamespace

import pytest

from firmware_builds import build, cli, run_program, write_model
from easylab.board.simtables import kept_symbols, state_tables
from easylab.codegen.device_state import layout_check_lines, packed_fields
from easylab.core import types as T
from easylab.core.errors import BuildError
from easylab.core.paths import runtime_dir

SOURCE = Path(__file__).with_name("own_chips")
MODEL = "own_state"
BOARDS = ("host", "avr", "pic18")
DURATION = "100ms"


@pytest.fixture(scope="module")
def builds(tmp_path_factory) -> dict:
    """The model folder copied outside the package, own_state built for
    every board (the MCUs' simulation builds), by board: the program to run."""
    out = tmp_path_factory.mktemp("state")
    folder = out / "own_chips"
    shutil.copytree(SOURCE, folder)
    programs = {"folder": folder}
    for board in BOARDS:
        built = build(folder / f"{MODEL}.elab", board, out / board, *(["--sim"] if board != "host" else []))
        programs[board] = built.simulator or built.executable
    return programs


def traces(builds: dict, stimulus: Path, out: Path, suffix: str = "csv", *flags: str,
           duration: str = DURATION) -> dict[str, bytes]:
    """The trace of each board and of local execution, by name."""
    got = {}
    for board in BOARDS:
        trace = out / f"{board}.{suffix}"
        run_program(builds[board], "--fast", "--duration", duration, "--stimulus", stimulus, "--trace", trace, *flags)
        got[board] = trace.read_bytes()
    trace = out / f"local.{suffix}"
    proc = cli("run", builds["folder"] / f"{MODEL}.elab", "--fast", "--duration", duration, "--stimulus", stimulus,
               "--trace", trace, *flags)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    got["local"] = trace.read_bytes()
    return got


def columns(csv: bytes) -> dict[str, list[str]]:
    rows = [row.split(",") for row in csv.decode().splitlines()]
    return {name: [row[k] for row in rows[1:]] for k, name in enumerate(rows[0])}


@pytest.mark.parametrize("suffix", ["csv", "vcd"])
def test_trace_state_is_the_same_in_every_mode_and_on_every_board(builds, tmp_path, suffix):
    got = traces(builds, builds["folder"] / f"{MODEL}.stimulus.csv", tmp_path, suffix, "--trace-state")
    assert got["avr"] == got["local"], "the AVR in simavr"
    assert got["pic18"] == got["local"], "the PIC18 in gpsim"
    assert got["host"] == got["local"], "the host firmware"
    if suffix == "vcd":
        assert b" inside.recent(3) $end" in got["local"]
        return
    cols = columns(got["local"])
    names = list(cols)
    # After the items, in device then field order; the array as one column per element.
    assert names[:5] == ["time_us", "wet", "dry", "inside.humidity", "outside.humidity"]
    assert names[5:12] == ["inside.next", "inside.reads", "inside.recent[0]", "inside.recent[1]", "inside.recent[2]",
                           "inside.recent[3]", "inside.trend"]
    assert names[-1] == "outside.failures"
    assert cols["inside.reads"] == [str(n) for n in range(1, 11)]  # one read per release of task sample
    assert set(cols["inside.trend"]) == {"-1", "0", "1"}
    assert len(set(cols["inside.recent[1]"])) >= 3 and len(set(cols["outside.recent[0]"])) >= 3
    assert set(cols["inside.failures"]) == {"0"}


def test_random_stimuli_give_one_state_trace_everywhere(builds, tmp_path):
    """Seeded stimuli nobody wrote by hand: humidities over the chip's whole
    range at random instants (some between the releases) for both sensors."""
    for seed in range(3):
        rng = random.Random(seed)
        times = sorted(rng.sample(range(1, 150), 12))
        lines = ["time_us,inside.humidity,outside.humidity", f"0,{rng.randint(0, 10000)},{rng.randint(0, 10000)}"]
        lines += [f"{t * 1000 + rng.choice([0, 0, 500])},{rng.choice([0, 10000, rng.randint(0, 10000)])},"
                  f"{rng.randint(0, 10000)}" for t in times]
        stimulus = tmp_path / f"s{seed}.csv"
        stimulus.write_text("\n".join(lines) + "\n")
        out = tmp_path / f"seed{seed}"
        out.mkdir()
        got = traces(builds, stimulus, out, "csv", "--trace-state", duration="160ms")
        assert got["avr"] == got["pic18"] == got["host"] == got["local"], f"seed {seed}:\n{stimulus.read_text()}"
        assert columns(got["local"])["inside.reads"][-1] == "16"


def test_without_the_option_no_state_is_traced(builds, tmp_path):
    got = traces(builds, builds["folder"] / f"{MODEL}.stimulus.csv", tmp_path)
    assert got["avr"] == got["pic18"] == got["host"] == got["local"]
    assert got["local"].splitlines()[0] == b"time_us,wet,dry,inside.humidity,outside.humidity"


@pytest.mark.parametrize("board", ["avr", "pic18"])
def test_the_harness_help_names_the_option(builds, board):
    said = run_program(builds[board], "--help").stdout
    assert "[--trace-state]" in said
    assert "--trace-state     the trace also records the devices' `state` fields (DEVICE.FIELD" in said


UNUSED = """\
model unused
device type Quiet(address: uint8 = 0x28) {
    claims i2c[0] addr address
    out humidity: uint16
    state kept: uint32
    driver "quiet" impl avr "quiet.c" sim "chip.c"
}
device q: Quiet()
var wet: uint16
dataflow D { q.humidity -> wet }
task t period 10 ms { run D }
"""


def test_a_state_no_code_uses_is_kept_and_traced_on_the_avr(tmp_path):
    """The AVR links with --gc-sections: a state its handlers never touch
    stays in a simulation build (kept_symbols), traced as zero."""
    quiet = "EL_READ {\n    uint8_t rx[2];\n    (void)el_i2c_transfer(0u, address, 0, 0u, rx, 2u);\n" \
            "    humidity = (uint16_t)(((uint16_t)rx[0] << 8) | rx[1]);\n}\n"
    chip = (SOURCE / "drivers" / "hygro_chip.c").read_text()
    model = write_model(tmp_path, UNUSED, {"quiet.c": quiet, "chip.c": chip})
    built = build(model, "avr", tmp_path / "avr", "--sim")
    stimulus = tmp_path / "s.csv"
    stimulus.write_text("time_us,q.humidity\n0,1234\n")
    run_program(built.simulator, "--fast", "--duration", "30ms", "--stimulus", stimulus, "--trace",
                tmp_path / "t.csv", "--trace-state")
    assert (tmp_path / "t.csv").read_text().splitlines()[:2] == ["time_us,wet,q.humidity,q.kept", "0,0,1234,0"]


def test_remote_refuses_trace_state_in_one_line_before_any_link(tmp_path):
    proc = cli("remote", SOURCE / f"{MODEL}.elab", "--target", "socket://127.0.0.1:9", "--fast", "--trace-state",
               "--trace", tmp_path / "t.csv", timeout=60)
    assert proc.returncode == 2
    assert proc.stderr == ("easylab remote: --trace-state: the devices' `state` fields live in the proxy's RAM on the "
                           "target and its UP frames carry only the devices' data; trace them with the firmware's or "
                           "`easylab run`'s --trace-state\n"), proc.stderr
    assert not (tmp_path / "t.csv").exists()


# ---------------------------------------------------------------- the layout the harness reads

SCALARS = [T.BOOL, T.INT8, T.UINT8, T.INT16, T.UINT16, T.INT32, T.UINT32, T.FLOAT32, T.TIME]


def _program(states: list) -> SimpleNamespace:
    """A program of one device running an AVR handler file with ``states``."""
    dev = SimpleNamespace(id=0, path="d", states=states, handlers={"avr": "d.c"})
    return SimpleNamespace(devices=[dev], items=[], charts=[])


def _natural_padding(states: list) -> bool:
    """Whether a compiler aligning each field to its size (x86-64 gcc) pads it."""
    offset, align = 0, 1
    for _name, t, size in states:
        width = t.bits // 8
        align = max(align, width)
        if offset % width:
            return True
        offset += width * (size or 1)
    return offset % align != 0


def _compiles(compiler: list[str], source: str, folder: Path) -> subprocess.CompletedProcess:
    src = folder / "layout.c"
    src.write_text(source)
    return subprocess.run([*compiler, "-Wall", "-Wextra", "-Werror", f"-I{runtime_dir()}", "-c", str(src), "-o",
                           str(folder / "layout.o")], capture_output=True, text=True)


def test_the_layout_check_holds_on_the_avr_and_catches_padding(tmp_path):
    """Seeded random states: the packed offsets are what avr-gcc lays out
    (the check compiles), and gcc on this machine, which aligns fields,
    refuses exactly the states it pads, naming the device."""
    rng = random.Random(7)
    padded_seen = 0
    for case in range(24):
        states = [(f"f{k}", rng.choice(SCALARS), rng.choice([None, None, 1, 2, 3, 4]))
                  for k in range(rng.randint(1, 6))]
        program = _program(states)
        offsets = [offset for _n, _t, _c, offset in packed_fields(program.devices[0])]
        assert offsets == [sum(t.bits // 8 * (s or 1) for _n, t, s in states[:k]) for k in range(len(states))]
        source = "\n".join(layout_check_lines(program, "avr")) + "\n"
        avr = _compiles(["avr-gcc", "-mmcu=atmega328p", "-std=gnu99"], source, tmp_path)
        assert avr.returncode == 0, f"case {case}: {states}\n{avr.stderr}"
        host = _compiles(["gcc", "-std=gnu99"], source, tmp_path)
        padded = _natural_padding(states)
        padded_seen += padded
        assert (host.returncode != 0) == padded, f"case {case}: {states}\n{host.stderr}"
        if padded:
            assert "el_mdev0_state_has_no_padding" in host.stderr
    assert 0 < padded_seen < 24


def test_a_missing_state_symbol_is_named():
    program = _program([("n", T.UINT16, None)])
    assert "el_mdev0_state" in kept_symbols(program, "avr")
    assert "el_mdev0_state" not in kept_symbols(program)
    with pytest.raises(BuildError, match="fw.elf: symbols the simulator needs are missing: el_mdev0_state"):
        state_tables(program, "avr", {}, "fw.elf")
    rows = state_tables(program, "avr", {"el_mdev0_state": (0x120, 2)}, "fw.elf")
    assert "    { 0x0120u, 2u }, /* el_mdev0_state.n */" in rows
