"""Compiling with gcc-style C compilers: what the host board, the AVR
board and any board whose compiler takes ``-I``/``-D``/``-c``/``-o``
share."""

from __future__ import annotations

import shutil
import subprocess
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from ..core.errors import BuildError
from ..core.paths import runtime_dir
from .description import BoardDescription, BoardError, read_description
from .registry import board_folders

# Which Debian package provides a compiler, for the message when it is missing
# (besides the compilers the boards found name in their board.toml).
DEBIAN_PACKAGES = {"gcc": "gcc", "cc": "gcc", "clang": "clang", "sdcc": "sdcc"}


def require_tool(tool: str, board: str, debian_package: str | None = None, what: str = "C compiler") -> None:
    """BuildError naming the tool and its Debian package when it is not on PATH."""
    if shutil.which(tool) is not None:
        return
    package = debian_package or DEBIAN_PACKAGES.get(Path(tool).name) or _package_named_by_a_board(tool)
    if package is None:
        raise BuildError(f"the {what} '{tool}' of board '{board}' is not installed (or not on PATH)")
    raise BuildError(f"the {what} '{tool}' of board '{board}' is not installed (Debian package: {package})")


def _package_named_by_a_board(tool: str) -> str | None:
    """The Debian package a board found names for its compiler ``tool``
    (``--cc`` may name another board's compiler)."""
    for found in board_folders().values():
        try:
            chain = read_description(found.folder).toolchain
        except BoardError:
            continue
        if Path(chain.cc).name == Path(tool).name and chain.debian_package:
            return chain.debian_package
    return None


def runtime_sources(release: bool, exclude: tuple[str, ...] = ()) -> list[Path]:
    """The runtime's C files a firmware compiles: a release build has no
    debug code at all (runtime_c/el_debug*.c are left out)."""
    return sorted(p for p in runtime_dir().glob("*.c")
                  if not (release and p.name.startswith("el_debug")) and p.name not in exclude)


def mode_flags(release: bool) -> list[str]:
    """EL_RELEASE or EL_DEBUG, which every runtime file reads."""
    return ["-DEL_RELEASE=1"] if release else ["-DEL_DEBUG=1"]


def dispatcher_width_flags(program) -> list[str]:
    """The program's narrowest dispatcher widths (its IR's ``tick_bits`` and
    ``task_mask_bits``, docs/ir.md), for a board that narrows them (8-bit
    parts: less flash and fewer cycles per instant). Every file of a build
    must see the same flags."""
    flags = [f"-DEL_TASK_MASK_BITS={program.task_mask_bits}"]
    if program.tick_bits == 16:
        flags.append("-DEL_TICK_16=1")
    return flags


def include_flags(out_dir: Path | None, description: BoardDescription) -> list[str]:
    """The generated files first, then the runtime, then the board's folders."""
    first = [f"-I{out_dir}"] if out_dir is not None else []
    return first + [f"-I{runtime_dir()}"] + [f"-I{d}" for d in description.include_paths]


def run(cmd: list[str], what: str, package: str | None = None) -> subprocess.CompletedProcess:
    """Run a tool; BuildError with its output when it fails or is missing."""
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True)
    except FileNotFoundError:
        hint = f" (Debian package: {package})" if package else ""
        raise BuildError(f"{cmd[0]} is not installed{hint}") from None
    if proc.returncode != 0:
        raise BuildError(f"{what} failed:\n{proc.stdout}{proc.stderr}".rstrip())
    return proc


def compile_objects(compiler: str, flags: list[str], sources: list[Path], obj_dir: Path,
                    generated_dir: Path | None = None, file_flags: dict | None = None) -> list[Path]:
    """Compile each source to an object in ``obj_dir``, in parallel; a
    generated file's object is NAME_gen.o so it cannot clash with a
    runtime or board file of the same name. ``file_flags``: further options
    of some runtime or board files, by file name, after ``flags`` (a
    generated file gets none: its name is the model's to choose)."""
    obj_dir.mkdir(parents=True, exist_ok=True)
    file_flags = file_flags or {}

    def one(src: Path) -> tuple[Path, subprocess.CompletedProcess]:
        generated = src.parent == generated_dir
        obj = obj_dir / (src.stem + ("_gen" if generated else "") + ".o")
        own = () if generated else file_flags.get(src.name, ())
        return obj, subprocess.run([compiler, *flags, *own, "-c", "-o", str(obj), str(src)], capture_output=True,
                                   text=True)

    with ThreadPoolExecutor(max_workers=4) as pool:
        results = list(pool.map(one, sources))
    failed = [p for _, p in results if p.returncode != 0]
    if failed:
        raise BuildError(f"{compiler} failed:\n" + "".join(p.stdout + p.stderr for p in failed).rstrip())
    return [obj for obj, _ in results]


def defined_symbols(nm: str, binary: Path, package: str | None = None) -> set[str]:
    """The names a linked program defines (``nm --defined-only``)."""
    out = run([nm, "--defined-only", str(binary)], nm, package).stdout
    return {parts[-1] for parts in (line.split() for line in out.splitlines()) if len(parts) >= 3}


def elf_sections(size_tool: str, elf: Path, package: str | None = None) -> dict[str, int]:
    """Section sizes of an ELF (``size -A``)."""
    sizes = {}
    for line in run([size_tool, "-A", str(elf)], size_tool, package).stdout.splitlines():
        parts = line.split()
        if len(parts) >= 2 and parts[0].startswith(".") and parts[1].isdigit():
            sizes[parts[0]] = int(parts[1])
    return sizes


def write_files(out_dir: Path, files: dict[str, str]) -> list[Path]:
    """Write generated files into ``out_dir``, leaving unchanged ones alone
    (their modification time then tells make-like tools nothing changed);
    returns their paths. The one writer of generated files."""
    written = []
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
        for name, text in files.items():
            path = out_dir / name
            if not path.exists() or path.read_text(encoding="utf-8") != text:
                path.write_text(text, encoding="utf-8")
            written.append(path)
    except OSError as err:
        raise BuildError(f"cannot write to {out_dir}: {err.strerror or err}") from None
    return written
