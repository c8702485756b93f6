"""The f16 board's proxies (docs/boards.md, "The F16 board"): what checks a
build here in place of Softune's fcc907s.

- the C89 front ends: ``gcc -std=c89 -pedantic-errors`` and clang for
  MSP430 (a 16-bit int, 32-bit long and 16-bit pointers, as the F2MC-16's
  medium model), each with ``-Wall -Wextra -Werror``; clang's objects give
  the size estimates and the symbols of a build;
- clang-tidy's checks for arithmetic that a 16-bit int breaks;
- sdcc for the 8051, whose image s51 runs: the 16-bit proxy
  (simulator.py).

Every check sees every C file a build compiles (the generated ones, the
runtime's, the board's) with the defines and include folders of the build.
"""

from __future__ import annotations

import re
import shutil
import subprocess
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from easylab.board.cbuild import compile_objects, defined_symbols, elf_sections, require_tool
from easylab.core.errors import BuildError
from easylab.board.sdcc_rescue import crashed, rescue_source

from . import stack8051

_PACKAGES = "gcc clang clang-tidy sdcc sdcc-libraries sdcc-ucsim"


def _spec(board) -> dict:
    return board.description.table("proxy")


def _tool(board, argv: list[str], what: str) -> list[str]:
    require_tool(argv[0], board.name, _spec(board).get("debian_packages", _PACKAGES), what)
    return list(argv)


def clang_objects(board, sources: list[Path], flags: list[str], obj_dir: Path, generated_dir: Path) -> list[Path]:
    """Compile with clang for MSP430 (C89, 16-bit int): objects for sizes
    and symbols; any warning fails the build."""
    cmd = _tool(board, _spec(board)["clang"], "16-bit C front end")
    return compile_objects(cmd[0], [*cmd[1:], "-Os", *flags], sources, obj_dir, generated_dir)


def gcc_check(board, sources: list[Path], flags: list[str], obj_dir: Path, generated_dir: Path) -> None:
    """gcc -std=c89 -pedantic-errors: C89 as ISO wrote it."""
    cmd = _tool(board, _spec(board)["gcc"], "C89 front end")
    compile_objects(cmd[0], [*cmd[1:], *flags], sources, obj_dir, generated_dir)


def tidy_check(board, sources: list[Path], flags: list[str]) -> None:
    """clang-tidy's checks for 16-bit arithmetic, with the MSP430 target:
    a finding fails the build, naming the file and line."""
    spec = _spec(board)
    tidy = _tool(board, ["clang-tidy"], "C checker")[0]
    checks = ",".join(["-*", *spec["clang_tidy_checks"]])
    target = [a for a in spec["clang"][1:] if not a.startswith("-W") and a != "-pedantic-errors"]
    proc = subprocess.run([tidy, "--quiet", f"--checks={checks}", "--warnings-as-errors=*", *map(str, sources), "--",
                           *target, *flags], capture_output=True, text=True)
    findings = [line for line in proc.stdout.splitlines() if re.search(r": (warning|error): ", line)]
    if proc.returncode != 0 or findings:
        raise BuildError("clang-tidy (a 16-bit int) found:\n" + ("\n".join(findings) or proc.stdout + proc.stderr))


def object_sizes(objects: list[Path]) -> tuple[int, int]:
    """(code and constants, static data) over the objects (GNU size reads
    MSP430's ELF objects)."""
    code = data = 0
    for obj in objects:
        for name, size in elf_sections("size", obj, "binutils").items():
            if name.startswith((".text", ".rodata")):
                code += size
            elif name.startswith((".data", ".bss")):
                data += size
    return code, data


def object_symbols(objects: list[Path]) -> set[str]:
    names: set[str] = set()
    for obj in objects:
        names |= defined_symbols("nm", obj, "binutils")
    return names


# ====================================================================== sdcc, the 8051

def sdcc_command(board) -> list[str]:
    return _tool(board, _spec(board)["sdcc"], "16-bit proxy compiler")


def sdcc_includes(board, first: list[Path]) -> list[str]:
    """sdcc's own float.h does not compile with --std-c89: the proxy's
    stands in for it (proxy/include)."""
    folder = board.description.folder
    return [f"-I{folder / 'proxy' / 'include'}", *(f"-I{d}" for d in first),
            *(f"-I{d}" for d in board.description.include_paths), f"-I{folder / 'proxy'}"]


def _rescued(sdcc: list[str], flags: list[str], src: Path, rel: Path,
             crash: subprocess.CompletedProcess) -> subprocess.CompletedProcess:
    """sdcc crashed on ``src``: compile it again as sdcc_rescue rewrites it;
    if that fails too, the failure says what sdcc did to the file."""
    pre = subprocess.run(["timeout", "300", *sdcc, *flags, "-E", str(src)], capture_output=True, text=True)
    report = (crash.stdout + crash.stderr).strip()
    try:
        text, changed = rescue_source(pre.stdout)
    except Exception as exc:  # pycparser's ParseError and the like: nothing to rewrite
        text, changed = "", 0
        report += f"\n(no rewrite: {exc})"
    if pre.returncode == 0 and changed:
        safe = rel.with_name(f"{rel.stem}.rescued.c")
        safe.write_text(text)
        proc = subprocess.run(["timeout", "300", *sdcc, *flags, "-c", "-o", str(rel), str(safe)],
                              capture_output=True, text=True)
        if not crashed(proc.returncode, proc.stdout + proc.stderr):
            return proc
    return subprocess.CompletedProcess(crash.args, 1, "", f"sdcc crashed compiling {src.name} (a fault of sdcc 4.2, "
                                       f"not of the C; docs/boards.md, \"When sdcc crashes\"): {report}\n")


def sdcc_link(board, sources: list[Path], flags: list[str], work: Path, name: str) -> Path:
    """Compile each source with sdcc (in parallel) and link NAME.ihx; a
    warning fails, and so does a program that does not fit the 8051's 64 KB
    of code, saying so. The image's stack bound goes beside it
    (stack8051)."""
    sdcc = sdcc_command(board)
    obj = work / "obj8051"
    if obj.exists():
        shutil.rmtree(obj)
    obj.mkdir(parents=True)

    def one(src: Path) -> tuple[Path, subprocess.CompletedProcess]:
        rel = obj / f"{src.stem}{'_gen' if src.parent == work else ''}.rel"
        proc = subprocess.run(["timeout", "300", *sdcc, *flags, "-c", "-o", str(rel), str(src)], capture_output=True,
                              text=True)
        if crashed(proc.returncode, proc.stdout + proc.stderr):
            proc = _rescued(sdcc, flags, src, rel, proc)
        return rel, proc

    with ThreadPoolExecutor(max_workers=4) as pool:
        results = list(pool.map(one, sources))
    failed = [p for _, p in results if p.returncode != 0 or "warning" in (p.stdout + p.stderr).lower()]
    if failed:
        raise BuildError("sdcc (the 16-bit proxy) failed:\n" + "".join(p.stdout + p.stderr for p in failed).rstrip())
    ihx = work / f"{name}.ihx"
    proc = subprocess.run(["timeout", "300", *sdcc, "--code-size", "65536", "--xram-size", "65280", "-o", str(ihx),
                           *(str(rel) for rel, _ in results)], capture_output=True, text=True)
    if proc.returncode != 0 or not ihx.exists():
        text = (proc.stdout + proc.stderr).strip()
        if "Insufficient" in text or "exceeds" in text or "overlap" in text.lower():
            raise BuildError(f"the program does not fit the 16-bit proxy's 8051 (64 KB of code, 64 KB of data):\n{text}")
        raise BuildError(f"linking the 16-bit proxy with sdcc failed:\n{text}")
    memory = [f for f in sdcc if f.startswith(("-m", "--model-", "--stack-"))]
    stack8051.write_report(sorted(obj.glob("*.asm")), ihx, stack8051.library_needs(sdcc, memory))
    return ihx


def sdcc_memory(ihx: Path) -> tuple[int, int]:
    """(code bytes, external RAM bytes) of a linked image, from sdcc's .mem."""
    text = ihx.with_suffix(".mem").read_text()
    code = re.search(r"ROM/EPROM/FLASH\s+\S+\s+\S+\s+(\d+)", text)
    xram = re.search(r"EXTERNAL RAM\s+\S+\s+\S+\s+(\d+)", text)
    return int(code.group(1)) if code else 0, int(xram.group(1)) if xram else 0


def sdcc_symbols(ihx: Path) -> set[str]:
    """The names a linked image defines (sdcc's .map: C names with a
    leading underscore)."""
    text = ihx.with_suffix(".map").read_text()
    return set(re.findall(r"^\s+[A-Z]:\s+[0-9A-F]+\s+_(\w+)", text, re.M))
