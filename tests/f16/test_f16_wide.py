"""runtime_c/el_wide.c, the 64-bit arithmetic in two 32-bit words that a
compiler without a 64-bit type (the f16 board's) runs instead of int64_t:
every operation against Python's integers, saturating at the 64-bit range
and dividing toward zero (C99 6.5.5), as el_wide.h's int64_t form does
(checked here too, compiled from the header). Compiled here for the host:
the proxy's traces (tests/boards) run it on the 8051."""

from __future__ import annotations

import ctypes
import math
import struct
import subprocess

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from firmware_builds import ROOT

M64 = 1 << 64
I32 = st.integers(-(1 << 31), (1 << 31) - 1)
U32 = st.integers(0, (1 << 32) - 1)
I64 = st.one_of(st.integers(-(1 << 63), (1 << 63) - 1), st.integers(-(1 << 40), 1 << 40), I32)
ADD, SUB, MUL, DIV = 0, 1, 2, 3


class W64(ctypes.Structure):
    _fields_ = [("lo", ctypes.c_uint32), ("hi", ctypes.c_uint32)]


@pytest.fixture(scope="module")
def lib(tmp_path_factory):
    so = tmp_path_factory.mktemp("wide") / "libelwide.so"
    subprocess.run(["gcc", "-std=c99", "-O2", "-Wall", "-Wextra", "-Werror", "-shared", "-fPIC",
                    f"-I{ROOT / 'runtime_c'}", "-o", str(so), str(ROOT / "runtime_c" / "el_wide.c")],
                   check=True, capture_output=True)
    lib = ctypes.CDLL(str(so))
    p = ctypes.POINTER(W64)
    for name, args, res in [("el_w64_set_i32", [p, ctypes.c_int32], None), ("el_w64_set_u32", [p, ctypes.c_uint32], None),
                            ("el_w64_set_f32", [p, ctypes.c_float], None),
                            ("el_w64_op", [p, ctypes.c_uint8, p], None),
                            ("el_w64_op_i32", [p, ctypes.c_uint8, ctypes.c_int32], None),
                            ("el_w64_op_u32", [p, ctypes.c_uint8, ctypes.c_uint32], None),
                            ("el_w64_sat_i32", [p, ctypes.c_int32, ctypes.c_int32], ctypes.c_int32),
                            ("el_w64_sat_u32", [p, ctypes.c_uint32, ctypes.c_uint32], ctypes.c_uint32),
                            ("el_w64_cmp", [p, p], ctypes.c_int8), ("el_w64_sign", [p], ctypes.c_int8)]:
        fn = getattr(lib, name)
        fn.argtypes, fn.restype = args, res
    return lib


def wide(v: int) -> W64:
    v %= M64
    return W64(v & 0xFFFFFFFF, v >> 32)


def value(w: W64) -> int:
    v = w.hi << 32 | w.lo
    return v - M64 if v >> 63 else v


def int64(v: int) -> int:
    v %= M64
    return v - M64 if v >> 63 else v


def sat64(v: int) -> int:
    return max(-(1 << 63), min((1 << 63) - 1, v))


def expected(a: int, op: int, b: int) -> int:
    if op == ADD:
        return sat64(a + b)
    if op == SUB:
        return sat64(a - b)
    if op == MUL:
        return sat64(a * b)
    if b == 0:
        return 0  # el_wide.h: x / 0 is 0
    q = abs(a) // abs(b)
    return sat64(q if (a < 0) == (b < 0) else -q)


# el_wide.h's int64_t form (el_wide.c's el_w_*): each operation through its macro.
NATIVE = r"""
#include "el_types.h"
#define OP(name, macro) int64_t name(int64_t w, int64_t v) { macro(w, v); return w; }
OP(w_add, EL_W_ADD_W) OP(w_sub, EL_W_SUB_W) OP(w_mul, EL_W_MUL_W) OP(w_div, EL_W_DIV_W)
OP(i_add, EL_W_ADD_I) OP(i_sub, EL_W_SUB_I) OP(i_mul, EL_W_MUL_I) OP(i_div, EL_W_DIV_I)
int64_t u_mul(int64_t w, uint32_t v) { EL_W_MUL_U(w, v); return w; }
int64_t u_add(int64_t w, uint32_t v) { EL_W_ADD_U(w, v); return w; }
"""
EXTREMES = [-(1 << 63), -(1 << 63) + 1, -(1 << 62), -(1 << 32), -(1 << 31), -1, 0, 1, (1 << 31) - 1, 1 << 31,
            (1 << 32) - 1, 1 << 32, 3037000499, 3037000500, -3037000500, (1 << 62), (1 << 63) - 1]


@pytest.fixture(scope="module")
def native(tmp_path_factory):
    folder = tmp_path_factory.mktemp("native-wide")
    (folder / "native.c").write_text(NATIVE)
    so = folder / "libnative.so"
    subprocess.run(["gcc", "-std=c99", "-O2", "-Wall", "-Wextra", "-Werror", "-fsanitize=undefined",
                    "-fno-sanitize-recover=all", "-shared", "-fPIC", f"-I{ROOT / 'runtime_c'}", "-o", str(so),
                    str(folder / "native.c"), str(ROOT / "runtime_c" / "el_wide.c")], check=True, capture_output=True)
    lib = ctypes.CDLL(str(so))
    for name in ("w_add", "w_sub", "w_mul", "w_div", "i_add", "i_sub", "i_mul", "i_div", "u_mul", "u_add"):
        fn = getattr(lib, name)
        fn.argtypes = [ctypes.c_int64, ctypes.c_uint32 if name.startswith("u_") else ctypes.c_int64]
        fn.restype = ctypes.c_int64
    return lib


@pytest.mark.parametrize("a", EXTREMES)
def test_both_forms_saturate_at_the_extremes(lib, native, a):
    """Every pair of extreme values, every operation: the software words and
    the int64_t form (under -fsanitize=undefined: no overflow) agree with
    the saturated exact result (UINT32_MAX * UINT32_MAX is not 1, nor 0)."""
    names = {ADD: "add", SUB: "sub", MUL: "mul", DIV: "div"}
    for b in EXTREMES:
        for op, name in names.items():
            want = expected(a, op, b)
            w, x = wide(a), wide(b)
            lib.el_w64_op(ctypes.byref(w), op, ctypes.byref(x))
            assert value(w) == want, (a, name, b)
            if b != 0 or op != DIV:
                assert getattr(native, f"w_{name}")(a, b) == want, (a, name, b)
            if -(1 << 31) <= b < (1 << 31):
                w = wide(a)
                lib.el_w64_op_i32(ctypes.byref(w), op, b)
                assert value(w) == want, (a, name, b)
                if b != 0 or op != DIV:
                    assert getattr(native, f"i_{name}")(a, b) == want, (a, name, b)
            if 0 <= b < (1 << 32):
                w = wide(a)
                lib.el_w64_op_u32(ctypes.byref(w), op, b)
                assert value(w) == want, (a, name, b)
                if op in (ADD, MUL):
                    assert getattr(native, f"u_{name}")(a, b) == want, (a, name, b)


@settings(max_examples=3000, deadline=None)
@given(I64, st.sampled_from([ADD, SUB, MUL, DIV]), I64)
def test_operations_on_two_wide_values(lib, native, a, op, b):
    w, x = wide(a), wide(b)
    lib.el_w64_op(ctypes.byref(w), op, ctypes.byref(x))
    assert value(w) == expected(a, op, b)
    if b != 0 or op != DIV:
        assert getattr(native, "w_" + ("add", "sub", "mul", "div")[op])(a, b) == expected(a, op, b)


@settings(max_examples=3000, deadline=None)
@given(I64, st.sampled_from([ADD, SUB, MUL, DIV]), I32, U32)
def test_operations_with_a_32_bit_value(lib, a, op, i, u):
    w = wide(a)
    lib.el_w64_op_i32(ctypes.byref(w), op, i)
    assert value(w) == expected(a, op, i)
    w = wide(a)
    lib.el_w64_op_u32(ctypes.byref(w), op, u)
    assert value(w) == expected(a, op, u)


@settings(max_examples=2000, deadline=None)
@given(I64, I32, I32, U32, U32)
def test_saturation_comparison_and_sign(lib, a, lo, hi, ulo, uhi):
    w = wide(a)
    assert lib.el_w64_sat_i32(ctypes.byref(w), lo, hi) == (lo if a < lo else hi if a > hi else a)
    assert lib.el_w64_sat_u32(ctypes.byref(w), ulo, uhi) == (ulo if a < ulo else uhi if a > uhi else a)
    x = wide(lo)
    assert lib.el_w64_cmp(ctypes.byref(w), ctypes.byref(x)) == (a > lo) - (a < lo)
    assert lib.el_w64_sign(ctypes.byref(w)) == (a > 0) - (a < 0)


@settings(max_examples=2000, deadline=None)
@given(st.floats(width=32, allow_nan=True, allow_infinity=True))
def test_a_float_truncates_toward_zero_and_saturates(lib, f):
    w = W64(0, 0)
    lib.el_w64_set_f32(ctypes.byref(w), f)
    if math.isnan(f):
        want = 0
    else:
        want = max(-(1 << 63), min((1 << 63) - 1, int(f) if math.isfinite(f) else (1 << 63 if f > 0 else -(1 << 64))))
    assert value(w) == want


def test_what_the_std_actors_meet(lib):
    """PID's widest intermediate: a 17-bit error times a 31-bit gain."""
    w = wide(0)
    lib.el_w64_set_i32(ctypes.byref(w), -65535)
    lib.el_w64_op_i32(ctypes.byref(w), MUL, 2147483647)
    lib.el_w64_op_i32(ctypes.byref(w), DIV, 1000)
    assert value(w) == -(65535 * 2147483647 // 1000)
    assert struct.calcsize("<II") == ctypes.sizeof(W64)
