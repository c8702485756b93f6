"""Measure the CPU a remote-execution proxy spends per release instant, in
its board's simulator, and the coefficients of the link budget's CPU term
(docs/remote.md, "Link budget"; boards/*/board.toml, [remote_cpu]).

A measurement builds the proxy with ``--sim``, runs it in the harness flat
out (``--fast``) against a scripted host in lock-step (this module: per
release instant the UP frame is awaited and a DOWN of zeros answers it)
for N and then 3N release instants, and takes the harness's ``--report``:
the cycles the CPU worked (all cycles but those spent waiting: asleep on
the AVR, the wait loops' bare iterations on the PIC18). The slope between
the two runs is the work per release instant: the tick interrupts, the
dispatcher, the device reads and writes, the UP frame built (CRC, COBS)
and sent, the DOWN received and decoded, the UART's interrupts; the
start-up, the handshake and STOP cancel out.

    .venv/bin/python tools/proxy_cpu.py pic18 [--mcu M] [--instants N]

measures the calibration models (one device kind each, over a proxy of
one digital input) and prints the board's [remote_cpu] section.
"""

from __future__ import annotations

import argparse
import math
import re
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path


from easylab.pipeline import lower_file
from easylab.remote.device_model import device_model
from easylab.remote.link import Link
from easylab.remote.proxy import build_proxy

# The link's rate of the measurements: at 115200 baud and below every byte
# received comes alone, each its own pass through the link's code; at 1
# Mbaud several come at a time and an instant takes fewer cycles.
CALIBRATION_BAUD = 115200
REPEATS = 3  # measurements per calibration model (their median)
HEADROOM = 1.05  # on every coefficient, over what was measured

_REPORT = re.compile(r"cycles (\d+) \(asleep (\d+)\), instants (\d+)")

# The calibration models' pins, per board: a digital input (every model
# has one: a proxy task reads it), then each device kind on its own.
PINS = {
    "pic18": {"din": "RD0", "din2": "RD3", "dout": "RD1", "pwm": "RC2", "motor": ("RC1", "RD4"),
              "encoder": ("RB0", "RB1"), "adc": 0},
    "avr": {"din": "PD4", "din2": "PD5", "dout": "PB0", "pwm": "PD6", "motor": ("PB1", "PB2"),
            "encoder": ("PD2", "PD3"), "adc": 0},
}

# Device kind -> (driver, its declaration in a calibration model).
def _kinds(pins: dict) -> dict[str, tuple[str, str]]:
    return {
        "digital_in": ("digital_in", f'device extra: DigitalIn(pin = "{pins["din2"]}")'),
        "digital_out": ("digital_out", f'device extra: DigitalOut(pin = "{pins["dout"]}")'),
        "pwm_out": ("pwm_out", f'device extra: PwmOut(pin = "{pins["pwm"]}")'),
        "motor": ("motor", f'device extra: Motor(pwm = "{pins["motor"][0]}", dir = "{pins["motor"][1]}")'),
        "encoder": ("encoder", f'device extra: Encoder(pin_a = "{pins["encoder"][0]}", '
                               f'pin_b = "{pins["encoder"][1]}")'),
        "analog_in": ("analog_in", f'device extra: AnalogIn(channel = {pins["adc"]})'),
    }


_WIRES = {"digital_in": "extra.level -> seen2", "digital_out": "button.level -> extra.level",
          "pwm_out": "d.y -> extra.duty", "motor": "d.y -> extra.speed", "encoder": "extra.count -> count",
          "analog_in": "extra.value -> raw"}


def calibration_model(board: str, kind: str | None, period_ms: int = 1) -> str:
    """The text of a calibration model: a digital input read by one task
    (``kind`` None), or that and one device of ``kind``."""
    pins = PINS[board]
    extra = "" if kind is None else _kinds(pins)[kind][1]
    wire = "" if kind is None else _WIRES[kind]
    return f"""model cal "A proxy's CPU: calibration"
import std
device button: DigitalIn(pin = "{pins['din']}")
{extra}
var seen: bool
var seen2: bool
var count: int32
var raw: uint16
dataflow Io {{
    d = Const<int16>(value = 300)
    button.level -> seen
    {wire}
}}
task io period {period_ms} ms {{ run Io }}
"""


def two_task_model(board: str, period_ms: int = 1) -> str:
    """Two digital inputs, each read by a task of its own (the same
    instants): the second task's share of an instant."""
    pins = PINS[board]
    return f"""model cal2 "A proxy's CPU: calibration, two tasks"
import std
device button: DigitalIn(pin = "{pins['din']}")
device extra: DigitalIn(pin = "{pins['din2']}")
var seen: bool
var seen2: bool
dataflow A {{
    button.level -> seen
}}
dataflow B {{
    extra.level -> seen2
}}
task a period {period_ms} ms {{ run A }}
task b period {period_ms} ms {{ run B }}
"""


@dataclass
class Measured:
    """A proxy's work per release instant (cycles of its CPU beyond its
    clock's interrupts: the slope between two runs), the share of the
    cycles its clock's interrupts take while it waits (``tick_share``), and
    the runs' (cycles, cycles worked, instants)."""

    cycles_per_instant: float
    tick_share: float
    runs: list[tuple[int, int, int]]


def _report(err: str) -> tuple[int, int, int]:
    """(cycles, cycles worked, instants) of the harness's --report."""
    m = _REPORT.search(err)
    if m is None:
        raise RuntimeError(f"no --report in the harness's output: {err[-500:]}")
    return int(m.group(1)), int(m.group(1)) - int(m.group(2)), int(m.group(3))


def tick_share(simulator: Path, cycles: int = 20_000_000) -> float:
    """The share of the cycles the proxy works while it waits for a host
    (before START): its clock's interrupts, which take their share of any
    period whatever the device model."""
    proc = subprocess.run([str(simulator), "--uart0", "null", "--fast", "--cycles", str(cycles), "--report"],
                          capture_output=True, text=True, timeout=300, stdin=subprocess.DEVNULL)
    total, worked, _ = _report(proc.stderr)
    return worked / total


def scripted_run(simulator: Path, program, work: Path, instants: int, baud: int) -> tuple[int, int, int]:
    """(cycles, cycles worked, instants) of the proxy in its harness (flat out)
    for ``instants`` release instants against a scripted lock-step host."""
    model = device_model(program)
    work.mkdir(parents=True, exist_ok=True)
    link_path = work / "link"
    # Paced by the wall clock where the harness can keep it (simavr): an
    # instant lasts the host's round trip, not what the harness would run
    # flat out meanwhile, so the clock's interrupts taken out are few.
    sim = subprocess.Popen([str(simulator), "--uart0", f"pty:{link_path}", "--report"],
                           stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, stdin=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 30
        while not link_path.exists():
            if sim.poll() is not None or time.monotonic() > deadline:
                raise RuntimeError(f"the harness did not open its link: {sim.communicate()[1]}")
            time.sleep(0.01)
        link = Link(str(link_path), model, baud)
        try:
            link.connect(10)
            link.start(lock_step=True)
            table = [i for i in model.instants if i.release]
            done = 0
            base = 0
            while done < instants:
                for instant in table:
                    if done >= instants:
                        break
                    tick = base + instant.tick
                    link.up(tick, 10)
                    mask = sum(1 << k for k in instant.release)
                    payload = bytes(model.down_payload(instant.release) - 4)
                    link.down(tick, mask, payload)
                    done += 1
                base += model.hyperperiod
            link.stop()
        finally:
            link.close()
    finally:
        sim.send_signal(signal.SIGTERM)
        err = sim.communicate(timeout=60)[1]
    return _report(err)


def measure(program, board: str, work: Path, mcu: str | None = None, instants: int = 100,
            baud: int = CALIBRATION_BAUD) -> Measured:
    """The proxy of ``program`` on ``board``, built with ``--sim`` at
    ``baud``: ``measure_built``."""
    built = build_proxy(program, board, work / "proxy", mcu=mcu, sim=True, baud=baud)
    return measure_built(built.simulator, program, work, instants, baud)


def measure_built(simulator: Path, program, work: Path, instants: int = 100,
                  baud: int = CALIBRATION_BAUD) -> Measured:
    """The proxy of ``program`` in its harness ``simulator``: its CPU
    cycles per release instant, the slope between ``instants`` and three
    times as many. The clock's interrupts are taken out at their share of
    the cycles (in lock-step an instant lasts as long as the host's round
    trip, in real time its period)."""
    share = tick_share(simulator)
    runs = [scripted_run(simulator, program, work / f"run{n}", n, baud) for n in (instants, 3 * instants)]
    (c1, w1, _), (c2, w2, _) = runs
    return Measured(((w2 - share * c2) - (w1 - share * c1)) / (2 * instants), share, runs)


def measure_text(text: str, board: str, work: Path, mcu: str | None = None, instants: int = 100,
                 repeats: int = REPEATS, baud: int = CALIBRATION_BAUD) -> Measured:
    """``measure`` for a model given as text (at ``baud``), the
    median of ``repeats`` measurements (the host's round trips, longer or
    shorter, leave some noise: the clock's interrupts meanwhile are taken
    out at their share, not one by one)."""
    work.mkdir(parents=True, exist_ok=True)
    path = work / "cal.elab"
    path.write_text(text)
    program, result = lower_file(path)
    if program is None:
        raise RuntimeError(result.report())
    return median_measurement(lambda n: measure(program, board, work / f"m{n}", mcu, instants, baud), repeats)


def median_measurement(measure_once, repeats: int = REPEATS) -> Measured:
    """The median, by cycles per instant, of ``measure_once(n)`` for n in
    range(``repeats``): one measurement's clock-interrupt correction moves
    with the host's round trips, which a loaded machine stretches."""
    found = sorted((measure_once(n) for n in range(repeats)), key=lambda m: m.cycles_per_instant)
    return found[len(found) // 2]


def calibrate(board: str, mcu: str | None = None, instants: int = 100, baud: int = CALIBRATION_BAUD) -> dict:
    """The coefficients of ``board`` (board.toml's [remote_cpu], rounded up
    with HEADROOM): ``instant``, a release instant of one proxy task that
    reads one device (its frames' fixed bytes, the dispatcher, the link's
    code); ``task``, each further task released at it; ``drivers``, each
    device's share by its driver (its read or its write and its data's
    bytes in the frames); ``clock_share``, the share of every cycle its
    clock's interrupts take at a 1 ms tick; all with the link at ``baud``."""
    measured = []
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        base = measure_text(calibration_model(board, None), board, work / "base", mcu, instants, baud=baud)
        measured.append(base)
        drivers = {}
        for kind in _kinds(PINS[board]):
            m = measure_text(calibration_model(board, kind), board, work / kind, mcu, instants, baud=baud)
            measured.append(m)
            drivers[kind] = m.cycles_per_instant - base.cycles_per_instant
            print(f"{kind}: {m.cycles_per_instant:.0f} cycles per instant ({drivers[kind]:+.0f})", file=sys.stderr)
        two = measure_text(two_task_model(board), board, work / "two_tasks", mcu, instants, baud=baud)
        measured.append(two)
        task = two.cycles_per_instant - base.cycles_per_instant - drivers["digital_in"]
        print(f"task: {two.cycles_per_instant:.0f} cycles per instant ({task:+.0f})", file=sys.stderr)
    # The base model's digital input is one more digital_in.
    instant = base.cycles_per_instant - drivers["digital_in"]
    share = max(m.tick_share for m in measured)
    return {"baud": baud, "clock_share": math.ceil(share * HEADROOM * 10000) / 10000,
            "instant": math.ceil(instant * HEADROOM), "task": math.ceil(task * HEADROOM),
            "drivers": {k: math.ceil(max(v, 0.0) * HEADROOM) for k, v in drivers.items()}}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("board", choices=sorted(PINS))
    parser.add_argument("--mcu")
    parser.add_argument("--instants", type=int, default=100)
    parser.add_argument("--baud", type=int, default=CALIBRATION_BAUD,
                        help=f"the link's rate of the measurements (default {CALIBRATION_BAUD})")
    args = parser.parse_args(argv)
    found = calibrate(args.board, args.mcu, args.instants, args.baud)
    print("[remote_cpu]")
    print(f"clock_share = {found['clock_share']}  # board.toml keeps the largest of its rates'")
    print(f"[remote_cpu.at_{found['baud']}]")
    for k in ("instant", "task"):
        print(f"{k} = {found[k]}")
    print(f"[remote_cpu.at_{found['baud']}.drivers]")
    for k, v in found["drivers"].items():
        print(f"{k} = {v}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
