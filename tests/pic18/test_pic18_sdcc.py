"""What sdcc 4.2's pic16 port gets wrong and how the board keeps it out of
the firmware (docs/boards.md, "What sdcc gets wrong"): a model that hits
each defect against the host board's trace in gpsim, and the board's
passes on the C and the assembly that do it."""

from __future__ import annotations

import pytest
from pycparser import c_generator, c_parser

from firmware_builds import build
from easylab.board.registry import board_module
from pic18_testlib import DATA, MODELS, pic18_build, run

boolconv = board_module("pic18", "boolconv")
TARGET = board_module("pic18", "sdcc").TARGET


@pytest.fixture(scope="module")
def defects(build_cache) -> dict:
    model = MODELS / "sdcc_defects.elab"
    return {"pic18": build_cache.get(("pic18-sdcc-defects",),
                                     lambda out: pic18_build(model, out, "--mcu", "pic18f4620", "--sim", "--release")),
            "host": build_cache.get(("host-sdcc-defects",), lambda out: build(model, "host", out))}


def test_the_defects_model_gives_the_host_trace(defects, tmp_path):
    """Compare with every operator and Select<bool> (a _Bool from a
    conditional expression), Counter (its input tested after stores to
    other banks)."""
    args = ["--fast", "--duration", "200ms", "--stimulus", DATA / "sdcc_defects.stimulus.csv"]
    run(defects["host"].executable, *args, "--trace", tmp_path / "host.csv")
    run(defects["pic18"].simulator, *args, "--trace", tmp_path / "pic18.csv")
    host = (tmp_path / "host.csv").read_text()
    assert (tmp_path / "pic18.csv").read_text() == host
    rows = [line.split(",") for line in host.splitlines()]
    columns = {name: [r[k] for r in rows[1:]] for k, name in enumerate(rows[0])}
    assert set(columns["lt"]) == set(columns["s"]) == {"0", "1"} and columns["pulses"][-1] == "4"


def _rewritten(source: str) -> str:
    ast = c_parser.CParser().parse("typedef _Bool bool;\ntypedef unsigned char uint8_t;\n" + source)
    boolconv.fix_bool_conversions(ast, TARGET)
    return c_generator.CGenerator().visit(ast)


def test_every_conversion_to_bool_compares_with_zero():
    out = _rewritten("""
        bool g; struct s { bool f; } st;
        static bool r(uint8_t v) { return v; }
        static void take(bool b) { (void)b; }
        void f(uint8_t v, bool a, bool c, int w) {
            bool l = v; g = a ? c : a; st.f = v & 2u; g |= v; take(w); g = (bool)w;
            g = a; g = w > 3; g = !v; g = a && w; g = 1; take(a); l = r(v); (void)l;
        }""")
    for converted in ("return v != 0;", "bool l = v != 0;", "g = ((a) ? (c) : (a)) != 0;", "st.f = (v & 2u) != 0;",
                      "g = (g | v) != 0;", "take(w != 0);", "g = w != 0;"):
        assert converted in out, (converted, out)
    for kept in ("g = a;", "g = w > 3;", "g = !v;", "g = a && w;", "g = 1;", "take(a);", "l = r(v);"):
        assert kept in out, (kept, out)


def test_a_bool_cast_left_in_the_assembly_is_made_right():
    """A conversion the C pass does not see (a hardware file): sdcc's
    `BTFSC STATUS,Z` after the bytes that set Z becomes `BTFSS`; a skip
    after anything else is not sdcc's conversion and stays."""
    asm = ("\n\tMOVF\tr0x00, W\n\tIORWF\tr0x01, W\n\tBTFSC\tSTATUS, 2\n\tMOVLW\t0x01\n\tMOVWF\t_g, B\n"
           "\tMOVLW\t0x00\n\tBTFSC\tSTATUS, 2\n\tMOVLW\t0x01\n")
    fixed, count = boolconv.fix_bool_casts_in_asm(asm)
    assert count == 1
    assert fixed.count("BTFSS\tSTATUS, 2") == 1 and fixed.count("BTFSC\tSTATUS, 2") == 1
    assert fixed.index("BTFSS") < fixed.index("MOVLW\t0x00")
