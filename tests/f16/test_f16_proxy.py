"""The f16 board's 16-bit proxy (docs/boards.md, "The F16 board"): what a
16-bit int changes shows on it, where a 32-bit host hides it.

models/product16.elab multiplies two uint16 300s twice. The language says
uint16 * uint16 is a uint16 (docs/language.md, "Arithmetic"), so its own
expression wraps to 24464 on every board: the generator's casts
(EL_WRAP_MUL) make the result independent of the target. The actor's inline
C `y = a * b` is C, where the promotions decide: int is 32 bits on the host
(90000) and 16 bits on the F2MC-16 and the 8051 (24464) - exactly what a
generator that forgot its casts would produce. The proxy's trace shows the
difference and clang-tidy names the line; both are what this file checks.
"""

from __future__ import annotations

import csv
import re
import subprocess
from pathlib import Path

import pytest

from firmware_builds import EXAMPLE_NAMES, build

HERE = Path(__file__).resolve().parent
PRODUCT = HERE / "models" / "product16.elab"


def trace(program: Path, out: Path, *args: str) -> list[dict]:
    proc = subprocess.run([str(program), "--fast", "--duration", "50ms", "--trace", str(out), *args],
                          capture_output=True, text=True, timeout=300, stdin=subprocess.DEVNULL)
    assert proc.returncode == 0, proc.stderr
    with out.open() as f:
        return list(csv.DictReader(f))


@pytest.fixture(scope="module")
def product(build_cache, tmp_path_factory):
    """The product16 traces of the host board and of the 16-bit proxy."""
    work = tmp_path_factory.mktemp("product16")
    host = build_cache.get(("host", "product16"), lambda out: build(PRODUCT, "host", out))
    proxy = build_cache.get(("f16", "product16", "--sim"), lambda out: build(PRODUCT, "f16", out, "--sim"))
    return trace(host.executable, work / "host.csv"), trace(proxy.simulator, work / "proxy.csv")


def test_the_languages_product_is_the_same_on_both(product):
    host, proxy = product
    assert [r["language"] for r in host] == [r["language"] for r in proxy] == ["0"] + ["24464"] * 4


def test_the_inline_c_product_differs_on_a_16_bit_int(product):
    host, proxy = product
    assert [r["inline_c"] for r in host] == ["0"] + ["90000"] * 4
    assert [r["inline_c"] for r in proxy] == ["0"] + ["24464"] * 4


def test_clang_tidy_names_the_product_that_a_16_bit_int_cuts(tmp_path):
    err = build(PRODUCT, "f16", tmp_path / "out", "--check", ok=False).proc.stderr
    assert err.startswith("easylab: error: clang-tidy (a 16-bit int) found:"), err
    found = re.search(r"(\S+/model\.c):(\d+):\d+: error: performing an implicit widening conversion to type "
                      r"'uint32_t' \(aka 'unsigned long'\) of a multiplication performed in type 'unsigned int' "
                      r"\[bugprone-implicit-widening-of-multiplication-result", err)
    assert found, err
    line = Path(found.group(1)).read_text().splitlines()[int(found.group(2)) - 1]
    assert "y = a * b;" in line


def test_the_runner_takes_the_host_boards_options_and_says_what_is_wrong(build_cache, tmp_path):
    proxy = build_cache.get(("f16", "product16", "--sim"), lambda out: build(PRODUCT, "f16", out, "--sim"))
    run = [str(proxy.simulator)]
    proc = subprocess.run([*run, "--help"], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0 and "16-bit proxy of the f16 board" in proc.stdout
    proc = subprocess.run([*run, "--trace"], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2 and "--trace: a value must follow" in proc.stderr
    proc = subprocess.run([*run, "--duration", "5 parsecs"], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2 and "--duration 5 parsecs:" in proc.stderr
    bad = tmp_path / "bad.csv"
    bad.write_text("time_us,nothing\n0,1\n")
    proc = subprocess.run([*run, "--stimulus", str(bad)], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2 and f"{bad}:1:" in proc.stderr
    # Without --duration a run only ends at --timeout: an error, said plainly.
    proc = subprocess.run([*run, "--timeout", "1"], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 1 and "did not end within 1 s of wall-clock time" in proc.stderr


@pytest.mark.parametrize("name", EXAMPLE_NAMES)
def test_every_examples_generated_c_passes_the_c89_checks(build_cache, name, tmp_path):
    """The examples do not fit the part (AVR pins), so their generated C is
    checked from their 16-bit proxy builds (which the conformance suite makes
    too): gcc -std=c89 -pedantic, clang for MSP430, clang-tidy."""
    from easylab.board.registry import board_module, load_board
    from easylab.core.paths import runtime_dir

    built = build_cache.example("f16", name, "--mcu", "mb90f543", "--sim")
    out = built.executable.parent
    proxy, board = board_module("f16", "proxy"), load_board("f16")
    sources = sorted(p for p in out.glob("*.c") if p.name not in ("f16p_run_model.c", "el_f16p_tables.c"))
    flags = ["-DEL_BOARD_STDINT", "-DEL_DEBUG=1", "-DEL_F16_PROXY", f"-I{out}", f"-I{runtime_dir()}",
             *(f"-I{d}" for d in board.description.include_paths)]
    proxy.gcc_check(board, sources, flags, tmp_path / "gcc", out)
    proxy.clang_objects(board, sources, flags, tmp_path / "clang", out)
    proxy.tidy_check(board, sources, flags)
    assert {p.name for p in sources} >= {"model.c", "debug_tables.c"}


def test_a_stack_that_overflows_the_8051_is_named_not_a_wrong_value(tmp_path):
    """200 bytes of locals fit every board but the proxy's 8051 (some 220
    bytes of stack, part of them the runtime's): its run stops at the
    stack's top and says the model does not fit, with the build's bound and
    the call chain, where it went on over the registers and traced 113 for
    6 before."""
    model = HERE / "models" / "deep_stack.elab"
    host = build(model, "host", tmp_path / "host")
    assert [r["out"] for r in trace(host.executable, tmp_path / "host.csv")] == ["0", "6"]
    proxy = build(model, "f16", tmp_path / "f16", "--sim")
    proc = subprocess.run([str(proxy.simulator), "--duration", "50ms", "--trace", str(tmp_path / "proxy.csv")],
                          capture_output=True, text=True, timeout=300, stdin=subprocess.DEVNULL)
    assert proc.returncode == 1, proc.stderr
    assert "the program's stack reached the top of the 8051's internal RAM" in proc.stderr
    assert "the model does not fit the 16-bit proxy" in proc.stderr
    bound = re.search(r"bounds its deepest call chain at (\d+) bytes of stack, (\d+) are free: (main -> .*)",
                      proc.stderr)
    assert bound and int(bound.group(1)) > int(bound.group(2)), proc.stderr
    assert "el_spec1_Scratch_0_step" in bound.group(3)


def test_the_stack_bound_follows_sdccs_frames(tmp_path):
    """stack8051 reads sdcc's assembly: a prologue of 200 bytes (0xc8, not
    -56), an argument cleanup (0xfb is -5), a call through a pointer."""
    import sys
    sys.path.insert(0, str(HERE.parents[1] / "boards" / "f16"))
    import stack8051

    asm = "\n".join([
        ";	function main", "_main:", "\tlcall\t_big", "\tpush\tacc", "\tlcall\t_args", "\tret",
        ";	function big", "_big:", "\tpush\t_bp", "\tmov\ta,sp", "\tmov\t_bp,a", "\tadd\ta,#0xc8", "\tmov\tsp,a",
        "\tmov\tsp,_bp", "\tpop\t_bp", "\tret",
        ";	function args", "_args:", "\tpush\tar2", "\tpush\tar3", "\tpush\tar4", "\tpush\tar5", "\tpush\tar6",
        "\tlcall\t_leaf", "\tmov\ta,sp", "\tadd\ta,#0xfb", "\tmov\tsp,a", "\tmov\tdptr,#_leaf", "\tlcall\t__sdcc_call_dptr",
        "\tret",
        ";	function leaf", "_leaf:", "\tpush\tacc", "\tpop\tacc", "\tret",
    ])
    program = stack8051.Program()
    stack8051.read_assembly(asm, program)
    bound = stack8051.StackBound(program, {})
    assert bound.need("_leaf") == 1
    assert bound.need("_big") == 201  # _bp and 200 bytes of locals
    assert bound.need("_args") == 5 + 2 + 1  # five arguments, the call, the leaf's push
    assert bound.need("_main") == 2 + 201
