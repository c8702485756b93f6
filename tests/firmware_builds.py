"""Building firmware as a user does (``python -m easylab build``), for every
suite: one builder, and a session cache so that a build several suites
need (an example on a board) is made once per test run, shared by the
test processes of ``pytest -n`` through a folder and file locks."""

from __future__ import annotations

import fcntl
import os
import pickle
import re
import subprocess
import sys
import threading
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = sorted((ROOT / "examples").glob("*.elab"))
EXAMPLE_NAMES = [p.stem for p in EXAMPLES]


def cli(*args, timeout: float = 300, cwd: Path | None = None, env: dict | None = None) -> subprocess.CompletedProcess:
    """``python -m easylab ARGS`` (text), with this interpreter and the
    inherited environment plus ``env``."""
    return subprocess.run([sys.executable, "-m", "easylab", *map(str, args)], capture_output=True, text=True,
                          cwd=cwd or ROOT, env={**os.environ, **(env or {})}, timeout=timeout,
                          stdin=subprocess.DEVNULL)


@dataclass
class Built:
    """A build: the CLI's result, the path on its last line, the simulator."""

    proc: subprocess.CompletedProcess
    executable: Path | None
    simulator: Path | None

    @property
    def elf(self) -> Path | None:
        return self.executable

    @property
    def lines(self) -> list[str]:
        return self.proc.stdout.strip().splitlines()

    @property
    def size_line(self) -> str:
        return next(line for line in self.lines if "flash" in line and "RAM" in line)


def build(model: Path | str, board: str, out: Path, *args: str, ok: bool = True, env: dict | None = None) -> Built:
    """``easylab build MODEL --board BOARD ARGS -o OUT``; ``ok``: must it succeed?"""
    proc = cli("build", model, "--board", board, *args, "-o", out, env=env)
    if not ok:
        assert proc.returncode != 0, f"build of {model} for {board} {' '.join(args)} should fail:\n{proc.stdout}"
        return Built(proc, None, None)
    assert proc.returncode == 0, f"build of {model} for {board} {' '.join(args)} failed:\n{proc.stdout}{proc.stderr}"
    executable = Path(proc.stdout.strip().splitlines()[-1])
    assert executable.exists(), proc.stdout
    sim = next((Path(line.split(": ", 1)[1]) for line in proc.stdout.splitlines()
                if line.startswith("simulator: ")), None)
    return Built(proc, executable, sim)


def run_program(exe: Path, *args, timeout: float = 120, ok: bool = True) -> subprocess.CompletedProcess:
    """A built program (a host firmware, a simulator) with ARGS; ``ok``: must
    it exit with status 0?"""
    proc = subprocess.run([str(exe), *map(str, args)], capture_output=True, text=True, timeout=timeout,
                          stdin=subprocess.DEVNULL)
    if ok:
        assert proc.returncode == 0, f"{exe.name} {' '.join(map(str, args))}: status {proc.returncode}\n{proc.stderr}"
    return proc


def write_model(folder: Path, text: str, files: dict[str, str] | None = None, name: str = "model.elab") -> Path:
    """A model file in ``folder`` and the files beside it (handler and impl
    files, imports), by path relative to the folder."""
    for rel, content in (files or {}).items():
        target = folder / rel
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_text(content, encoding="utf-8")
    path = folder / name
    path.write_text(text, encoding="utf-8")
    return path


_INTERFACE = {"debug": re.compile(r"^\s*debug\b"), "modbus-rtu": re.compile(r"^\s*modbus\s+rtu\b")}


def board_conformance(board: str, board_path: list[str] | tuple[str, ...] = ()) -> tuple[Path | None, dict]:
    """A board's folder and its board.toml [conformance] table ((None, {})
    for a mode that is not a board, as the interpreter)."""
    import tomllib

    from easylab.board.registry import board_folders

    found = board_folders(board_path).get(board)
    if found is None:
        return None, {}
    return found.folder, tomllib.loads((found.folder / "board.toml").read_text()).get("conformance", {})


def board_model(board: str, model: Path, interface: str, out: Path) -> Path:
    """The model a suite runs on a board: ``model`` itself, but on a board
    whose [conformance] table names an ``interface_uart`` (a part with one
    UART, as the PIC18's EUSART) the board's variant of it (its folder's
    ``variants``: the part's pins, no interface line) with the one interface
    the suite tests, ``debug`` or ``modbus-rtu``, as the model declares it
    but on that UART, and no other (a model without a variant keeps its
    lines)."""
    folder, table = board_conformance(board)
    uart = table.get("interface_uart")
    if uart is None:
        return model
    variant = folder / table.get("variants", "conformance") / model.name
    base = (variant if variant.is_file() else model).read_text(encoding="utf-8").splitlines(keepends=True)
    wanted = [line for line in model.read_text(encoding="utf-8").splitlines(keepends=True)
              if _INTERFACE[interface].match(line)]
    lines = [line for line in base if not any(p.match(line) for p in _INTERFACE.values())
             and not line.lstrip().startswith("modbus tcp")]
    lines += [re.sub(r"\bon\s+uart\d+", f"on {uart}", line) for line in wanted]
    out.mkdir(parents=True, exist_ok=True)
    path = out / model.name
    path.write_text("".join(lines), encoding="utf-8")
    return path


def end_process(proc: subprocess.Popen, timeout: float = 30.0) -> tuple[str, str]:
    """End a firmware or simulator as a user would (SIGTERM: its files are
    complete then), killed if it does not end within ``timeout``; its
    (stdout, stderr), None for what was not captured."""
    import signal

    if proc.poll() is None:
        proc.send_signal(signal.SIGTERM)
    try:
        return proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.kill()
        return proc.communicate()


def stimulus_of(name: str) -> Path | None:
    """An example's own stimulus (examples/NAME.stimulus.csv), if it has one."""
    path = ROOT / "examples" / f"{name}.stimulus.csv"
    return path if path.is_file() else None


class BuildCache:
    """Builds made once per run, by key; safe to fill from threads and from
    the parallel test processes sharing ``root``. A result that can be
    pickled is shared through ``root``; one that cannot is made again, in
    a folder of this process's own (``private``), by each process."""

    def __init__(self, root: Path, private: str = "own"):
        self.root = root
        self.private = private
        self._lock = threading.Lock()
        self._entries: dict[tuple, tuple[threading.Lock, list]] = {}

    def get(self, key: tuple, make: Callable[[Path], object]):
        """The result of ``make(out_dir)`` for ``key``, made on first use."""
        with self._lock:
            lock, slot = self._entries.setdefault(key, (threading.Lock(), []))
        with lock:
            if not slot:
                slot.append(self._shared("-".join(str(k).replace("/", "_") for k in key), make))
            return slot[0]

    def _shared(self, name: str, make: Callable[[Path], object]):
        self.root.mkdir(parents=True, exist_ok=True)
        out, result_file = self.root / name, self.root / f"{name}.result"
        private = self.root / f"{name}.private"
        with open(self.root / f"{name}.lock", "a") as lock_file:
            fcntl.flock(lock_file, fcntl.LOCK_EX)  # released when the file closes
            if result_file.exists():
                return pickle.loads(result_file.read_bytes())
            if private.exists():  # another process's result, in use there
                return make(self.root / self.private / name)
            result = make(out)
            try:
                result_file.write_bytes(pickle.dumps(result))
            except (pickle.PicklingError, TypeError, AttributeError):
                private.touch()
            return result

    def example(self, board: str, name: str, *args: str, env: dict | None = None) -> Built:
        """An example built for a board with ARGS (``--mcu M``, ``--sim``, ...)."""
        return self.get((board, name, *args),
                        lambda out: build(ROOT / "examples" / f"{name}.elab", board, out, *args, env=env))
