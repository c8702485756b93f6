"""The interpreter's C arithmetic against the C runtime itself: integer
division and remainder (el_arith.c), wrapping, saturating time, float32
operations, and float32 literals as gcc rounds them."""

from __future__ import annotations

import itertools
import math
import random
import struct
import subprocess

import pytest

from easylab.core import types as T
from easylab.core.paths import runtime_dir
from easylab.interp import values as V
from easylab.interp.exprs import ExprCompiler
from easylab.core import expr as I


def _run_c(tmp_path, body: str) -> list[str]:
    source = tmp_path / "probe.c"
    source.write_text('#include <stdio.h>\n#include <string.h>\n#include "el_types.h"\n'
                      f"int main(void) {{\n{body}\nreturn 0;\n}}\n")
    exe = tmp_path / "probe"
    subprocess.run(["gcc", "-std=c99", "-O2", f"-I{runtime_dir()}", str(source), str(runtime_dir() / "el_arith.c"),
                    "-o", str(exe)], check=True, capture_output=True)
    return subprocess.run([str(exe)], check=True, capture_output=True, text=True).stdout.split()


def _edge_values(t: T.ValueType) -> list[int]:
    values = {0, 1, 2, 3, 7, t.min, t.max, t.min + 1, t.max - 1}
    if t.signed:
        values |= {-1, -2, -3, -7}
    return sorted(values)


@pytest.mark.parametrize("t", list(T.INTEGERS), ids=lambda t: t.name)
def test_integer_arithmetic_is_el_arith(t, tmp_path):
    values = _edge_values(t)
    pairs = list(itertools.product(values, values))
    suffix = {"int8": "i8", "int16": "i16", "int32": "i32", "uint8": "u8", "uint16": "u16", "uint32": "u32"}[t.name]
    unsigned = t.c_name if not t.signed else "u" + t.c_name
    lines = []
    for a, b in pairs:
        la, lb = f"(({t.c_name}){a}LL)", f"(({t.c_name}){b}LL)"
        for expr in (f"el_div_{suffix}({la}, {lb})", f"el_mod_{suffix}({la}, {lb})",
                     f"EL_WRAP_ADD({t.c_name}, {unsigned}, {la}, {lb})", f"EL_WRAP_SUB({t.c_name}, {unsigned}, {la}, {lb})",
                     f"EL_WRAP_MUL({t.c_name}, {unsigned}, {la}, {lb})", f"EL_WRAP_NEG({t.c_name}, {unsigned}, {la})"):
            lines.append(f'printf("%lld\\n", (long long){expr});')
    got = _run_c(tmp_path, "\n".join(lines))
    wrap, div, mod = V.wrapper(t), V.div_integer(t), V.mod_integer(t)
    expected = []
    for a, b in pairs:
        expected += [div(a, b), mod(a, b), wrap(a + b), wrap(a - b), wrap(a * b), wrap(-a)]
    assert [int(x) for x in got] == expected


def test_time_saturates(tmp_path):
    values = [0, 1, 5, 1000, 2 ** 31, 2 ** 32 - 2, 2 ** 32 - 1]
    pairs = list(itertools.product(values, values))
    got = _run_c(tmp_path, "\n".join(f'printf("%lu %lu\\n", (unsigned long)el_time_add({a}u, {b}u), '
                                     f'(unsigned long)el_time_sub({a}u, {b}u));' for a, b in pairs))
    assert [int(x) for x in got] == [v for a, b in pairs for v in (V.time_add(a, b), V.time_sub(a, b))]


def _bits(x: float) -> int:
    return struct.unpack("<I", struct.pack("<f", x))[0] if math.isfinite(x) or math.isnan(x) else \
        (0x7F800000 if x > 0 else 0xFF800000)


def test_float32_operations(tmp_path):
    """Every operation rounded once to single precision (computing in double
    first is exact for + - * /), el_div_f32's x / 0 = 0, and NaNs."""
    rnd = random.Random(7)
    specials = [0.0, -0.0, 1.0, -1.0, 0.1, 3.4028234663852886e38, 1.401298464324817e-45, math.inf, -math.inf,
                math.nan, 16777217.0, 1e-30, -2.5]
    values = [V.f32(v) for v in specials] + [V.f32(rnd.uniform(-1, 1) * 10.0 ** rnd.randint(-45, 38))
                                            for _ in range(25)]
    pairs = list(itertools.product(values, values))
    decl = "float a, b; unsigned int u; float r;\n"
    lines = [decl]
    ops = (("+", V.add_f32), ("-", V.sub_f32), ("*", V.mul_f32))
    for a, b in pairs:
        lines.append(f"u = {_bits(a)}u; memcpy(&a, &u, 4); u = {_bits(b)}u; memcpy(&b, &u, 4);")
        for op, _ in ops:
            lines.append(f'r = a {op} b; memcpy(&u, &r, 4); printf("%u\\n", u);')
        lines.append('r = el_div_f32(a, b); memcpy(&u, &r, 4); printf("%u\\n", u);')
    got = [int(x) for x in _run_c(tmp_path, "\n".join(lines))]
    expected = [_bits(fn(a, b)) for a, b in pairs for fn in (*(f for _, f in ops), V.div_f32)]
    nan = {0x7FC00000, 0xFFC00000}
    for g, e in zip(got, expected):
        assert g == e or (g in nan and e in nan), (hex(g), hex(e))  # NaN signs: see the equivalence tests
    assert sum(g == e for g, e in zip(got, expected)) > len(got) * 0.99


def test_float32_literals_round_like_gcc(tmp_path):
    """A float32 literal is the C backend's decimal text rounded once by the
    compiler; values near float32 halfway points catch double rounding."""
    rnd = random.Random(3)
    doubles = []
    for _ in range(300):
        f = abs(V.f32(rnd.uniform(-1, 1) * 10.0 ** rnd.randint(-40, 38)))
        ulp = V.f32_from_bits(V.f32_bits(f) + 1) - f  # of float32
        halfway = f + ulp / 2  # exact in double
        doubles.append(rnd.choice([1, -1]) * rnd.choice([halfway, math.nextafter(halfway, 0),
                                                          math.nextafter(halfway, math.inf)]))
    doubles += [0.1, 1 / 3, 3.4028235677973366e38, 1e-46, 7e-46]
    texts = [repr(float(d)) for d in doubles]
    assert sum(V.literal(T.FLOAT32, d) != V.f32(d) for d in doubles) > 30  # rounding twice would differ
    got = _run_c(tmp_path, "float r; unsigned int u;\n" + "\n".join(
        f'r = {text}f; memcpy(&u, &r, 4); printf("%u\\n", u);' for text in texts))
    assert [int(x) for x in got] == [_bits(V.literal(T.FLOAT32, d)) for d in doubles]


def test_compiled_expressions():
    """A few expressions through the compiler: wrap at the node type,
    division rules, conversions, step references."""
    i16, u8 = T.INT16, T.UINT8

    def item(t, n):
        return I.Ref(t, "item", n, f"x{n}")
    e = I.Binary(i16, "+", item(i16, 0), I.Const(i16, 32767), i16)
    f = ExprCompiler().compile(e)
    assert f([[1]], None, None) == -32768
    e = I.Binary(i16, "/", I.Convert(i16, item(u8, 1)), item(i16, 0), i16)
    assert ExprCompiler().compile(e)([[0], [200]], None, None) == 0
    assert ExprCompiler().compile(e)([[-3], [200]], None, None) == -66
    e = I.Binary(T.BOOL, "and", I.Ref(T.BOOL, "step_active", 1, "B.active"),
                 I.Binary(T.BOOL, ">", I.Ref(T.TIME, "step_time", 1, "B.time"), I.Const(T.TIME, 20), T.TIME), T.BOOL)
    g = ExprCompiler(step_slots=[0, 1]).compile(e)
    assert g([], [0, 30], [0, 1]) is True
    assert g([], [0, 30], [0, None]) is False
    # A stored value converts as a C assignment: an int16 into an int8 wraps.
    assert ExprCompiler().compile(item(i16, 0), T.INT8)([[200]], None, None) == -56
