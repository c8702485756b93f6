"""``easylab build``: generate C for a board and compile it with the board's
toolchain into build/<model>/<board>/."""

from __future__ import annotations

import importlib
import shutil
import subprocess
from dataclasses import dataclass, field
from pathlib import Path

from . import cgen
from .boards import Board, load_board, runtime_dir, templates_dir
from .ir import Program


# Which Debian package provides a compiler, for the message when it is missing.
_DEBIAN_PACKAGES = {"gcc": "gcc", "cc": "gcc", "clang": "clang", "avr-gcc": "gcc-avr", "sdcc": "sdcc"}


class BuildError(Exception):
    """A build that cannot go on; the message is one clear line (or the
    compiler's output)."""


@dataclass
class BuildResult:
    out_dir: Path
    executable: Path  # the host program, or a cross board's ELF
    sources: list[Path]
    notes: list[str] = field(default_factory=list)  # printed before the path (a cross board's sizes)
    simulator: Path | None = None  # a cross board's simulator build (--sim)


def write_files(out_dir: Path, files: dict[str, str]) -> list[Path]:
    """Write generated files into ``out_dir``, leaving unchanged ones alone
    (their modification time then tells make-like tools nothing changed)."""
    written = []
    for name, text in files.items():
        path = out_dir / name
        if not path.exists() or path.read_text(encoding="utf-8") != text:
            path.write_text(text, encoding="utf-8")
        written.append(path)
    return written


def generate(program: Program, board: Board, out_dir: Path, release: bool = False) -> list[Path]:
    """Write the generated files (C sources, maps); returns their paths."""
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
        return write_files(out_dir, cgen.render(program, board, templates_dir(), release))
    except OSError as err:
        raise BuildError(f"cannot write to {out_dir}: {err.strerror or err}") from None


def compile_host_like(program: Program, board: Board, out_dir: Path, generated: list[Path],
                      extra_cflags: list[str] | None = None, cc: str | None = None, release: bool = False) -> Path:
    """Compile and link the generated code, the runtime and the board's port."""
    compiler = cc or board.cc
    if shutil.which(compiler) is None:
        package = _DEBIAN_PACKAGES.get(Path(compiler).name, board.debian_package if compiler == board.cc else None)
        if package is None:
            raise BuildError(f"the C compiler '{compiler}' is not installed (or not on PATH)")
        raise BuildError(f"the C compiler '{compiler}' of board '{board.name}' is not installed "
                         f"(Debian package: {package})")
    # A release build has no debug code at all: the debug server's files
    # (runtime_c/el_debug*.c) are left out and EL_RELEASE is defined.
    runtime = sorted(p for p in runtime_dir().glob("*.c") if not (release and p.name.startswith("el_debug")))
    generated = [p for p in generated if p.suffix == ".c"]
    board_sources = [board.path / s for s in board.sources]
    includes = [f"-I{runtime_dir()}", f"-I{out_dir}"] + [f"-I{board.path / d}" for d in board.include_dirs]
    exe = out_dir / program.name
    mode = ["-DEL_RELEASE=1"] if release else ["-DEL_DEBUG=1"]
    cmd = [compiler, *board.cflags, *mode, *(extra_cflags or []), *includes, "-o", str(exe),
           *map(str, generated + runtime + board_sources), *board.ldflags]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        raise BuildError(f"{compiler} failed:\n{proc.stdout}{proc.stderr}".rstrip())
    return exe


def backend_of(board: Board):
    """The generator module of a cross board (board.toml `backend`, a module
    of this package such as avrgen), or None for host-like boards."""
    name = board.raw.get("backend")
    if not name:
        return None
    try:
        return importlib.import_module(f".{name}", __package__)
    except ImportError as err:
        raise BuildError(f"board '{board.name}': its backend module '{name}' cannot be loaded: {err}") from None


def build(program: Program, board_name: str, out_dir: Path, extra_cflags: list[str] | None = None,
          cc: str | None = None, release: bool = False, mcu: str | None = None, sim: bool = False,
          schedule: str | None = None) -> BuildResult:
    """Generate and compile ``program`` for a board. A release build has no
    debug interface (the debug server is linked into debug builds only).
    Cross boards (a `backend` in board.toml) also take an MCU, check the
    model's resource claims, report sizes and build a simulator (``sim``)."""
    board = load_board(board_name)
    backend = backend_of(board)
    if backend is None:
        if mcu is not None or sim:
            raise BuildError(f"board '{board.name}' has no {'MCU choice (--mcu)' if mcu else 'simulator (--sim)'}")
        generated = generate(program, board, out_dir, release)
        exe = compile_host_like(program, board, out_dir, generated, extra_cflags, cc, release)
        return BuildResult(out_dir, exe, generated)
    board = backend.configure(board, mcu, sim)
    checked = backend.check(program, board)
    generated = generate(program, board, out_dir, release)
    generated += backend.produce(program, board, out_dir, release, checked)
    exe, report = backend.compile(program, board, out_dir, generated, extra_cflags, cc, release, schedule)
    result = BuildResult(out_dir, exe, generated, list(report.lines))
    if sim:
        result.simulator, warnings = backend.build_simulator(program, board, out_dir, exe)
        result.notes += warnings + [f"simulator: {result.simulator}"]
    return result
