"""Helpers of the native (generated C) tests: the CLI, builds, runs, traces.

Everything goes through the ``easylab`` command line as a user would run
it (``python -m easylab`` with this interpreter and the inherited
environment), then through the built host program.
"""

from __future__ import annotations

import csv
import io
import os
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
DATA = HERE / "data"
EXAMPLES = sorted((ROOT / "examples").glob("*.elab"))
EXAMPLE_NAMES = [p.stem for p in EXAMPLES]
SANITIZE = "-fsanitize=address,undefined -fno-sanitize-recover=all"

M32 = 0xFFFFFFFF


def cli(*args, env: dict | None = None, cwd: Path | None = None, timeout: float = 300) -> subprocess.CompletedProcess:
    """``python -m easylab ARGS``; returns the CompletedProcess (text)."""
    return subprocess.run([sys.executable, "-m", "easylab", *map(str, args)], capture_output=True, text=True,
                          cwd=cwd or ROOT, env=dict(os.environ) if env is None else env, timeout=timeout,
                          stdin=subprocess.DEVNULL)


def build(model: Path, out: Path, *, cflags: str | None = None, schedule: str | None = None,
          cc: str | None = None, env: dict | None = None) -> Path:
    """Build ``model`` for the host board into ``out``; the executable."""
    args = ["build", model, "--board", "host", "-o", out]
    if cflags:
        args += [f"--cflags={cflags}"]  # joined: a value starting with '-' is not an option
    if schedule:
        args += ["--schedule", schedule]
    if cc:
        args += ["--cc", cc]
    proc = cli(*args, env=env)
    assert proc.returncode == 0, f"easylab {' '.join(map(str, args))} failed:\n{proc.stdout}{proc.stderr}"
    exe = Path(proc.stdout.strip().splitlines()[-1])
    assert exe.is_file() and os.access(exe, os.X_OK), proc.stdout
    return exe


@dataclass
class Run:
    proc: subprocess.CompletedProcess
    trace_text: str

    @property
    def trace(self) -> "Trace":
        return Trace(self.trace_text)


def run(exe: Path, trace: Path, *, duration: str, stimulus: Path | None = None, fast: bool = True,
        clean: bool = True, timeout: float = 120) -> Run:
    """Run a host program; with ``clean``, insist on exit status 0 and an
    empty stderr (the sanitizers report there)."""
    cmd = [str(exe)] + (["--fast"] if fast else []) + ["--duration", duration, "--trace", str(trace)]
    if stimulus is not None:
        cmd += ["--stimulus", str(stimulus)]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, stdin=subprocess.DEVNULL)
    if clean:
        assert proc.returncode == 0, f"{' '.join(cmd)}: exit status {proc.returncode}\n{proc.stderr}"
        assert proc.stderr == "", f"{' '.join(cmd)} wrote to stderr:\n{proc.stderr}"
    return Run(proc, trace.read_text(encoding="utf-8") if trace.exists() else "")


class Trace:
    """A CSV trace of the host board: rows only where something changed, so
    the value of a column at time t is that of the last row at or before t."""

    def __init__(self, text: str) -> None:
        rows = list(csv.reader(io.StringIO(text)))
        assert rows and rows[0][0] == "time_us", text[:200]
        self.header = rows[0]
        self.columns = {name: i for i, name in enumerate(self.header)}
        self.rows = [r for r in rows[1:]]
        self.times = [int(r[0]) for r in self.rows]
        assert self.times == sorted(self.times) and len(set(self.times)) == len(self.times), "times not increasing"

    def _row_at(self, t_us: int) -> list[str]:
        lo, hi = 0, len(self.times)
        while lo < hi:
            mid = (lo + hi) // 2
            if self.times[mid] <= t_us:
                lo = mid + 1
            else:
                hi = mid
        assert lo > 0, f"no trace row at or before {t_us} us"
        return self.rows[lo - 1]

    def raw(self, column: str, t_us: int) -> str:
        return self._row_at(t_us)[self.columns[column]]

    def int(self, column: str, t_us: int) -> int:
        return int(self.raw(column, t_us))

    def __call__(self, column: str, t_ms: float):
        """The value of a column at a time in ms: an int, or the text of a
        chart's activity."""
        text = self.raw(column, round(t_ms * 1000))
        if column.endswith(".active"):
            return text
        return int(text)

    def changes(self, column: str) -> list[tuple[int, str]]:
        """(time_us, value) at every change of a column, the first row included."""
        out = []
        i = self.columns[column]
        for t, r in zip(self.times, self.rows):
            if not out or out[-1][1] != r[i]:
                out.append((t, r[i]))
        return out


def cdiv(a: int, b: int) -> int:
    """C integer division: truncates toward zero."""
    q = abs(a) // abs(b)
    return q if (a >= 0) == (b >= 0) else -q


def clamp(v, lo, hi):
    return lo if v < lo else hi if v > hi else v


def write_stimulus(path: Path, header: list[str], rows: list[list]) -> Path:
    text = ",".join(header) + "\n" + "".join(",".join("" if c is None else str(c) for c in r) + "\n" for r in rows)
    path.write_text(text, encoding="utf-8")
    return path


def read_stimulus(path: Path) -> tuple[list[str], list[list[str]]]:
    rows = [r for r in csv.reader(path.read_text(encoding="utf-8").splitlines()) if r]
    return [h.strip() for h in rows[0]], [[c.strip() for c in r] for r in rows[1:]]


class Stimulus:
    """A stimulus file read back: device data as step functions, param and
    var writes as events (``docs``: boards/host/README.md)."""

    def __init__(self, path: Path) -> None:
        self.header, self.rows = read_stimulus(path)

    def level(self, column: str, t_us: int, default=0) -> int:
        """A device datum's value as read at time t_us (latest row <= t)."""
        i = self.header.index(column)
        value = default
        for r in self.rows:
            if int(r[0]) <= t_us and r[i] != "":
                value = int(r[i])
        return value

    def writes(self, column: str) -> list[tuple[int, int]]:
        """(time_us, value) of every cell of a param/var column."""
        i = self.header.index(column)
        return [(int(r[0]), int(r[i])) for r in self.rows if r[i] != ""]

    def param(self, column: str, release_us: int, tick_us: int, initial: int) -> int:
        """The value of a param (or an untouched var) latched by a release at
        release_us, when writes apply at the first instant (multiple of
        tick_us, every tick being an instant) at or after their time."""
        value = initial
        for t, v in self.writes(column):
            applies = -(-t // tick_us) * tick_us
            if applies <= release_us:
                value = v
        return value


# ---------------------------------------------------------------------- a reference SDF interpreter


class Sdf:
    """Synchronous dataflow as docs/ir.md defines it, independently of the
    generator: FIFO edges (a port feeding several edges gives each every
    token), initial tokens, one iteration = every node fires its repetition
    count, in any order the tokens allow (the values do not depend on it).

    ``add(name, fire, inputs, outputs)``: ``inputs``/``outputs`` map port
    names to rates; ``fire(tokens_by_input_port) -> tokens_by_output_port``
    keeps its own state. A var is a node with one input of rate 1 that
    records what it receives."""

    def __init__(self) -> None:
        self.nodes: dict[str, tuple] = {}
        self.edges: list[dict] = []

    def add(self, name, fire, inputs: dict[str, int], outputs: dict[str, int]) -> None:
        self.nodes[name] = (fire, dict(inputs), dict(outputs))

    def connect(self, src: str, sport: str, dst: str, dport: str, initial=()) -> None:
        self.edges.append({"src": src, "sport": sport, "dst": dst, "dport": dport, "fifo": list(initial)})

    def repetitions(self) -> dict[str, int]:
        """The smallest positive solution of the balance equations, per
        connected component."""
        from fractions import Fraction
        from math import gcd, lcm

        q: dict[str, int] = {}
        for start in self.nodes:
            if start in q:
                continue
            part: dict[str, Fraction] = {start: Fraction(1)}
            todo = [start]
            while todo:
                n = todo.pop()
                for e in self.edges:
                    prod = self.nodes[e["src"]][2][e["sport"]]
                    cons = self.nodes[e["dst"]][1][e["dport"]]
                    if e["src"] == n and e["dst"] not in part:
                        part[e["dst"]] = part[n] * prod / cons
                        todo.append(e["dst"])
                    elif e["dst"] == n and e["src"] not in part:
                        part[e["src"]] = part[n] * cons / prod
                        todo.append(e["src"])
            scale = lcm(*(f.denominator for f in part.values()))
            ints = {n: int(f * scale) for n, f in part.items()}
            g = 0
            for v in ints.values():
                g = gcd(g, v)
            q.update({n: v // g for n, v in ints.items()})
        for e in self.edges:
            assert q[e["src"]] * self.nodes[e["src"]][2][e["sport"]] == \
                q[e["dst"]] * self.nodes[e["dst"]][1][e["dport"]], "inconsistent rates"
        return q

    def iterate(self, q: dict[str, int]) -> None:
        left = dict(q)
        progress = True
        while progress and any(left.values()):
            progress = False
            for name, (fire, inputs, outputs) in self.nodes.items():
                while left[name]:
                    ins = [e for e in self.edges if e["dst"] == name]
                    if any(len(e["fifo"]) < inputs[e["dport"]] for e in ins):
                        break
                    taken = {}
                    for e in ins:
                        rate = inputs[e["dport"]]
                        taken[e["dport"]], e["fifo"][:] = e["fifo"][:rate], e["fifo"][rate:]
                    produced = fire(taken)
                    for port, rate in outputs.items():
                        assert len(produced[port]) == rate
                    for e in self.edges:
                        if e["src"] == name:
                            e["fifo"].extend(produced[e["sport"]])
                    left[name] -= 1
                    progress = True
        assert not any(left.values()), f"deadlock: {left}"


class VarSink:
    """An `out:` node of a var: keeps the last token (one per activation)."""

    def __init__(self) -> None:
        self.value = 0

    def __call__(self, tokens):
        self.value = tokens["x"][-1]
        return {}
