"""runtime_c/el_wide.c, the 64-bit arithmetic in two 32-bit words that a
compiler without a 64-bit type (the f16 board's) runs instead of int64_t:
every operation against Python's integers, wrapping at 64 bits and dividing
toward zero as int64_t does (C99 6.5.5). Compiled here for the host: the
proxy's traces (tests/boards) run it on the 8051."""

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


def expected(a: int, op: int, b: int) -> int:
    if op == ADD:
        return int64(a + b)
    if op == SUB:
        return int64(a - b)
    if op == MUL:
        return int64(a * b)
    if b == 0:
        return 0  # el_wide.h: x / 0 is 0
    q = abs(a) // abs(b)
    return int64(q if (a < 0) == (b < 0) else -q)


@settings(max_examples=3000, deadline=None)
@given(I64, st.sampled_from([ADD, SUB, MUL, DIV]), I64)
def test_operations_on_two_wide_values(lib, a, op, b):
    w, x = wide(a), wide(b)
    lib.el_w64_op(ctypes.byref(w), op, ctypes.byref(x))
    assert value(w) == expected(a, op, b)


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
