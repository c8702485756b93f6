"""Bad models a careless or hostile author may write: numbers beyond any
type, names and strings too long, file names the system refuses, line
ends inside strings. Each is a diagnostic with file:line:col, never a
traceback; each class is also tried over its whole range by hypothesis.
"""

from __future__ import annotations

import re

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from easylab.pipeline import check_file
from firmware_builds import build, write_model

# The documented limits (docs/language.md, "Lexical structure").
MAX_NAME_LENGTH = 63
MAX_STRING_BYTES = 255

SETTINGS = settings(max_examples=60, deadline=None, derandomize=True, database=None,
                    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])


def errors(result) -> list[tuple[int, int, str]]:
    return [(d.span.line, d.span.column, d.message) for d in result.diagnostics.sorted()]


# ------------------------------------------------------------------ numbers

@pytest.mark.parametrize("declaration, column", [
    ("param f: float32 = 1e309", 20),
    ("param f: float32 = -1e400", 20),
    ("param f: float32 = 1.0 range 0.0..1e309", 35),
    ("const c: float32 = 1e300 * 1e300", 20),
])
def test_a_real_beyond_a_double_is_an_error_at_its_place(check_model, declaration, column):
    result, _ = check_model(f'model m "t"\n{declaration}\n')
    assert [(line, col) for line, col, _ in errors(result)] == [(2, column)]
    assert "is beyond the range of 'float32'" in errors(result)[0][2]


@pytest.mark.parametrize("text", ["1e309", "-1e400"])
def test_the_command_line_reports_a_real_beyond_a_double_in_one_diagnostic(cli, tmp_path, text):
    path = write_model(tmp_path, f'model m "t"\nparam f: float32 = {text}\n')
    proc = cli("check", path)
    assert proc.returncode != 0 and "Traceback" not in proc.stderr + proc.stdout
    assert re.search(r"model\.elab:2:20: error: .* is beyond the range of 'float32'", proc.stdout + proc.stderr)


REAL = st.builds(lambda sign, mantissa, exponent: f"{sign}{mantissa}e{exponent}",
                 st.sampled_from(["", "-"]), st.sampled_from(["1", "9.99", "3.4028236", "0.5", "17"]),
                 st.integers(-400, 400))
PLACES = ["param f: float32 = {x}", "param f: float32 = 0.0 range {x}..{x}", "const c: float32 = {x}",
          "param f: float32 = 0.0 range -1.0..{x}", "const c: float32 = {x} * {x}", "const c: float32 = {x} / 3.0",
          "param t: time = {x} s", "task main period {x} ms {{ }}", "param i: int32 = 0 range 0..{x}"]


@SETTINGS
@given(REAL, st.sampled_from(PLACES))
def test_any_real_anywhere_is_accepted_or_an_error_never_an_exception(tmp_path, real, place):
    result = check_file(write_model(tmp_path, f'model m "t"\n{place.format(x=real)}\n'))
    for line, col, message in errors(result):
        assert line == 2 and col >= 1 and message


# ------------------------------------------------------------------ file names

@pytest.mark.parametrize("name, column, message", [
    ("x" * 300 + ".c", 10, "string of 302 bytes in UTF-8, more than the 255 a string may have"),
    ("x" * 240 + "/" + "y" * 3 + ".c", 5, "not found"),
    ("a\\0b.c", 5, "not found"),
])
def test_an_impl_file_name_the_system_refuses_is_an_error_at_its_place(check_model, cli, name, column, message):
    text = f'model m "t"\nactor type A() {{\n    out y: int16\n    impl "{name}"\n}}\n'
    result, path = check_model(text)
    assert [(line, col) for line, col, _ in errors(result)] == [(4, column)]
    assert message in errors(result)[0][2]
    proc = cli("build", path, "--board", "host", "-o", path.parent / "out")
    assert proc.returncode != 0 and "Traceback" not in proc.stderr + proc.stdout
    assert f"model.elab:4:{column}: error: " in proc.stdout + proc.stderr


# ------------------------------------------------------------------ names and strings

def test_a_name_of_4096_characters_is_an_error_at_its_place(check_model):
    result, _ = check_model(f'model m "t"\nparam {"p" * 4096}: int16 = 1\n')
    assert errors(result) == [(2, 7, f"name '{'p' * 20}...' has 4096 characters, more than the "
                                     f"{MAX_NAME_LENGTH} a name may have")]


@SETTINGS
@given(st.integers(MAX_NAME_LENGTH + 1, 5000), st.sampled_from([
    "param {n}: int16 = 1", "var {n}: int8", "const {n}: int16 = 1", "dataflow {n} {{ }}",
    "task {n} period 1 ms {{ }}", "device {n}: DigitalOut(pin = \"PB5\")"]))
def test_every_name_longer_than_the_limit_is_an_error(tmp_path, length, declaration):
    name = "n" * length
    result = check_file(write_model(tmp_path, f'model m "t"\nimport std\n{declaration.format(n=name)}\n'))
    assert [(line, message.split(" has ")[1]) for line, _, message in errors(result)] == \
        [(3, f"{length} characters, more than the {MAX_NAME_LENGTH} a name may have")]


def test_names_of_the_longest_length_build_for_the_host(tmp_path):
    def name(start: str) -> str:
        return start + "x" * (MAX_NAME_LENGTH - len(start))

    model, param, led, flow, wave, task = (name(s) for s in ("m", "p", "led", "Flow", "wave", "task"))
    path = write_model(tmp_path, f"""model {model} "t"
import std
param {param}: uint16 = 500 range 10..5000 service rw
device {led}: DigitalOut(pin = "PB5")
dataflow {flow} {{
    {wave} = SquareWave(half_period = {param})
    {wave}.y -> {led}.level
}}
task {task} period 1 ms {{ run {flow} }}
debug on uart0
modbus rtu on uart1
""")
    result = check_file(path)
    assert not result.diagnostics.has_errors, result.report()
    build(path, "host", tmp_path / "out")


@pytest.mark.parametrize("size", [MAX_STRING_BYTES + 1, 5000])
def test_a_string_longer_than_the_limit_is_an_error_at_its_place(check_model, size):
    result, _ = check_model(f'model m "{"é" * (size // 2)}{"x" * (size % 2)}"\n')
    assert errors(result) == [(1, 9, f"string of {size} bytes in UTF-8, more than the {MAX_STRING_BYTES} a "
                                     "string may have")]


# ------------------------------------------------------------------ line ends

def test_a_lone_carriage_return_in_a_string_is_the_same_error_given_as_text(tmp_path):
    path = tmp_path / "m.elab"
    path.write_bytes(b'model m "a\rb"\n')
    from_file = errors(check_file(path))
    from_text = errors(check_file(path, text='model m "a\rb"\n'))
    assert from_file == from_text == [(1, 9, "string is never closed: a string ends with '\"' on the same line")]


@settings(max_examples=80, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.lists(st.sampled_from(['model m "a"', "\r", "\n", "\r\n", '"', "param p: int8 = 1", " ", "x", "\ufeff",
                                 "// c", "/* ", " */"]), max_size=12))
def test_a_text_given_in_memory_gets_the_diagnostics_of_its_file(tmp_path, parts):
    text = "".join(parts)
    path = tmp_path / "m.elab"
    path.write_bytes(text.encode("utf-8"))
    assert errors(check_file(path, text=text)) == errors(check_file(path))
