"""What sdcc 4.2's pic16 port gets wrong and how the board keeps it out of
the firmware (docs/boards.md, "What sdcc gets wrong"): a model that hits
each defect against the host board's trace in gpsim, and the board's
passes on the C and the assembly that do it."""

from __future__ import annotations

from pathlib import Path

import pytest
from pycparser import c_generator, c_parser

from firmware_builds import build
from easylab.board.registry import board_module
from easylab.core.errors import BuildError
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


def test_the_bank_check_finds_a_banked_access_under_another_bank(tmp_path):
    """A read of an object larger than a bank after a store to another of
    its banks, its BANKSEL dropped (sdcc's --obanksel=9 did): a fault; with
    the BANKSEL, after a call (BSR unknown) without one, at a label joining
    two banks: faults; a skip's both ways and a branch's target followed."""
    linkmap = board_module("pic18", "linkmap")
    bankcheck = board_module("pic18", "bankcheck")
    lmap = linkmap.LinkMap(symbols={"_big": (0x300, "data", "m.asm"), "_v": (0x080, "data", "m.asm")})
    asm_file = tmp_path / "m.asm"

    def faults(body: str) -> list:
        return bankcheck.check("S_m__f\tcode\n_f:\n" + body, asm_file, lmap)

    store = "\tBANKSEL\t(_big + 590)\n\tMOVWF\t(_big + 590), B\n"
    read = "\tMOVF\t(_big + 10), W, B\n"
    found = faults(store + read)
    assert [(f.needs, f.bsr) for f in found] == [(3, 5)] and "(_big + 10)" in str(found[0])
    assert faults(store + "\tBANKSEL\t(_big + 10)\n" + read) == []
    assert len(faults("\tBANKSEL\t(_big + 10)\n\tCALL\t_g\n" + read)) == 1
    joined = "\tBANKSEL\t_v\n\tBZ\t_L1\n\tBANKSEL\t(_big + 10)\n_L1:\n" + read
    assert len(faults(joined)) == 1
    skip = "\tBANKSEL\t(_big + 10)\n\tBTFSC\tr0x00, 0\n\tBANKSEL\t_v\n" + read
    assert len(faults(skip)) == 1
    assert faults("\tBANKSEL\t(_big + 10)\n\tBTFSC\tr0x00, 0\n\tINCF\tr0x01, F\n" + read) == []
    assert faults("\tMOVLB\t0x03\n" + read) == []


def test_an_error_in_an_actors_c_names_the_model_line_and_the_actor(tmp_path):
    """sdcc compiles lowered C (obj/model_gen.sdcc.c); its `#line` markers
    and model.c's actor comments bring a message back to the model."""
    from pic18_testlib import write_model

    model = write_model(tmp_path, "vla", """actor type Vla() {
    in  x: uint8
    out y: uint8
    step {{
        { uint8_t v[x + 1u]; v[0] = x; y = v[0]; }
    }}
}

param x: uint8 = 1
var y: uint8

dataflow D {
    a = Vla()
    x -> a.x
    a.y -> y
}

task main period 10 ms { run D }
""")
    built = pic18_build(model, tmp_path / "b", "--release", ok=False)
    out = built.proc.stdout + built.proc.stderr
    assert f"{model}:8: error" in out and f"(in actor type Vla, {model}:4;" in out, out
    assert ".sdcc.c:" not in out.replace("compiling model_gen.sdcc.c", ""), out


def test_a_shift_by_8_or_more_becomes_shifts_by_7_at_most():
    shifts = board_module("pic18", "shifts")
    ast = c_parser.CParser().parse("unsigned long f(unsigned long x) { return (x << 27) + (x << 7) + (x << 8u); }")
    assert shifts.split_shifts(ast) == 2
    out = c_generator.CGenerator().visit(ast)
    assert "(((x << 7u) << 7u) << 7u) << 6u" in out and "(x << 7)" in out and "(x << 7u) << 1u" in out, out


def test_a_file_sdcc_crashes_on_is_compiled_again_with_fewer_optimisations(tmp_path):
    """An sdcc that crashes as 4.2 did on some model.c (SDCCopt.c's assert)
    unless its pCode optimisations are off: the file compiles on the next
    try, the build says so, and sdcc's internal error is not the message;
    a crash on every try names the file, not sdcc's internals."""
    sdcc = board_module("pic18", "sdcc")
    real = sdcc.find_toolchain()
    fake = tmp_path / "tc"
    (fake / "bin").mkdir(parents=True)
    (fake / "share").symlink_to(real.root / "share")
    script = fake / "bin" / "sdcc"
    script.write_text("#!/bin/sh\ncase \" $* \" in *\" -S \"*) case \" $* \" in *\" --no-peep \"*) ;; *)\n"
                      "  echo \"Internal error: FATAL Compiler Internal Error in file 'SDCCopt.c' line number '834'"
                      "\" >&2; exit 1;; esac;; esac\n"
                      f"exec {real.sdcc} \"$@\"\n")
    script.chmod(0o755)
    source = tmp_path / "f.c"
    source.write_text("unsigned char g;\nvoid f(void) { g++; }\n")
    build = sdcc.Build(sdcc.Toolchain(fake), "18f4620", [], [], tmp_path / "obj",
                       Path(sdcc.__file__).parent / "el_pic18_w64.h")
    obj = build.compile_one(source)
    assert obj.is_file() and any("sdcc crashed; compiled with" in n and "--no-peep" in n for n in build.notes)
    script.write_text("#!/bin/sh\ncase \" $* \" in *\" -S \"*)\n"
                      "  echo \"FATAL Compiler Internal Error\" >&2; exit 1;; esac\n"
                      f"exec {real.sdcc} \"$@\"\n")
    source.write_text("unsigned char g;\nvoid f(void) { g += 2; }\n")  # another text: not from the build cache
    with pytest.raises(BuildError) as err:
        build.compile_one(source)
    assert "sdcc failed on f.c (it crashed" in str(err.value) and "SDCCopt" not in str(err.value)


def test_initializers_of_zeros_are_dropped():
    """sdcc put every initialised RAM object of a file in one section,
    which gplink must place in one 256-byte bank: a model with more than a
    bank of items (72 int32 vars) did not link. Start-up clears RAM, so
    initializers of zeros go; others and read-only tables stay."""
    quirks = board_module("pic18", "sdcc_quirks")
    ast = c_parser.CParser().parse("""
        typedef long int32_t;
        int32_t a = 0; struct { int x; unsigned char y[3]; void *p; } s = {0, {0, 0, 0}, (void *)0};
        int b = 3; const int c = 0; static int d[2] = {0, 1}; extern int e;""")
    assert quirks.drop_zero_initializers({"m": ast}) == 2
    out = c_generator.CGenerator().visit(ast)
    for kept in ("int32_t a;", "int b = 3;", "const int c = 0;", "static int d[2] = {0, 1};"):
        assert kept in out, out
    assert "= {0, {0, 0, 0}" not in out
