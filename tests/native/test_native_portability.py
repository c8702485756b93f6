"""Portability of the C: the runtime (runtime_c/*.c) and the files generated
for every example compile without a single warning with gcc and clang
(C99, pedantic), avr-gcc (ATmega2560), a 16-bit-int front end (clang for
MSP430, syntax only) and sdcc (STM8).

Include paths: runtime_c, boards/host (el_board.h) and the build folder of
the example (generated headers such as el_debug_config.h). The runtime is
compiled against the generated headers of a debug build and of a release
build (`--release`: no debug server), with the mode macro `easylab build`
passes.
"""

from __future__ import annotations

import shutil
import subprocess
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from native_testlib import EXAMPLES, ROOT, cli

RUNTIME = ROOT / "runtime_c"
HOST = ROOT / "boards" / "host"
WARN = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic"]

COMPILERS = {
    "gcc": (["gcc", *WARN, "-c"], "gcc"),
    "clang": (["clang", *WARN, "-c"], "clang"),
    "avr-gcc": (["avr-gcc", "-mmcu=atmega2560", "-Os", *WARN, "-c"], "avr-gcc"),
    "msp430": (["clang", "--target=msp430-none-elf", *WARN, "-fsyntax-only"], "clang"),
    "sdcc": (["timeout", "120", "sdcc", "-mstm8", "--std-c99", "-c"], "sdcc"),
}


# `easylab build` compiles debug builds with -DEL_DEBUG=1 and release builds
# with -DEL_RELEASE=1 (generator/build.py); the same here.
MODE = {"debug": "-DEL_DEBUG=1", "release": "-DEL_RELEASE=1"}


@pytest.fixture(scope="module")
def sources(sanitized, tmp_path_factory) -> list[tuple[Path, Path, str]]:
    """(C file, folder of its generated headers, build mode) for everything
    to compile: the generated C of every example's debug build (the
    sanitized builds) and release build, and the runtime in both modes."""
    root = tmp_path_factory.mktemp("release_gen")

    def release(model: Path) -> Path:
        out = root / model.stem
        proc = cli("build", model, "--board", "host", "--release", "-o", out, "--cflags=-O0")
        assert proc.returncode == 0, proc.stderr
        return out

    with ThreadPoolExecutor(max_workers=2) as pool:
        releases = list(pool.map(release, EXAMPLES))
    out = []
    for gen, mode in [(exe.parent, "debug") for exe in sanitized.values()] + [(r, "release") for r in releases]:
        out += [(c, gen, mode) for c in sorted(gen.glob("*.c"))]
    for gen, mode in ((next(iter(sanitized.values())).parent, "debug"), (releases[0], "release")):
        out += [(c, gen, mode) for c in sorted(RUNTIME.glob("*.c"))]
    return out


def compile_one(kind: str, source: Path, gen: Path, mode: str) -> str | None:
    """None when the file compiles silently, else the compiler's complaint."""
    cmd, _ = COMPILERS[kind]
    with tempfile.TemporaryDirectory(prefix="el_port_") as work:
        args = [*cmd, MODE[mode], f"-I{RUNTIME}", f"-I{HOST}", f"-I{gen}", str(source)]
        if kind == "sdcc":
            args += ["-o", work + "/"]
        elif kind != "msp430":
            args += ["-o", str(Path(work) / "out.o")]
        proc = subprocess.run(args, capture_output=True, text=True, cwd=work, timeout=300)
    text = (proc.stdout + proc.stderr).strip()
    if proc.returncode != 0 or (kind != "sdcc" and proc.stderr.strip()) or "warning" in text.lower():
        return f"{source} ({gen.name}, {mode}): exit {proc.returncode}\n{text}"
    return None


@pytest.mark.parametrize("kind", list(COMPILERS))
def test_compiles_without_warnings(kind, sources):
    tool = COMPILERS[kind][1]
    if shutil.which(tool) is None:
        pytest.skip(f"{tool} is not installed")
    with ThreadPoolExecutor(max_workers=2) as pool:
        problems = [p for p in pool.map(lambda s: compile_one(kind, *s), sources) if p]
    assert not problems, "\n\n".join(problems)
    assert sum(s.name == "model.c" for s, _, _ in sources) == 2 * len(EXAMPLES)
