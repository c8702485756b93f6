"""Model strings in the generated C (titles, the model's name from its file
name, file names in locations): whatever they hold, they reach C only
through c_syntax.c_string and c_syntax.c_comment, so the C compiles without
a warning and a string literal keeps the string's bytes (docs/language.md,
"Strings in the generated C")."""

from __future__ import annotations

import subprocess

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from easylab.codegen.c_syntax import c_comment, c_string
from firmware_builds import build, write_model

CFLAGS = ["-std=c99", "-pedantic", "-Wall", "-Wextra", "-Werror", "-Wtrigraphs", "-Wcomment"]
STRINGS = st.text(st.characters(codec="utf-8"), max_size=40) | st.sampled_from(
    ["*/", "/*", "??/", "??=", "\\", '"', "\u202e", "\0", "*/ int injected = 1; /*", "a\nb", "?\\?/", "*\\/"])


@settings(max_examples=40, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(STRINGS)
def test_a_string_compiles_without_warning_and_keeps_its_bytes(tmp_path, text):
    source = tmp_path / "s.c"
    source.write_text(f"""#include <stdio.h>
/* {c_comment(text)} */
static const char s[] = {c_string(text)};
int main(void)
{{
    size_t i;
    for (i = 0; i + 1 < sizeof s; i++)
        printf("%02x", (unsigned)(unsigned char)s[i]);
    return 0;
}}
""", encoding="ascii")
    exe = tmp_path / "s"
    compiled = subprocess.run(["gcc", *CFLAGS, "-o", str(exe), str(source)], capture_output=True, text=True)
    assert compiled.returncode == 0, compiled.stderr
    printed = subprocess.run([str(exe)], capture_output=True, text=True, check=True).stdout
    assert printed == text.encode("utf-8", "surrogatepass").hex()


def _elab_string(text: str) -> str:
    """``text`` as a string literal of the language (its escapes)."""
    escapes = {"\\": "\\\\", '"': '\\"', "\n": "\\n", "\r": "\\r", "\t": "\\t", "\0": "\\0"}
    return '"' + "".join(escapes.get(ch, ch) for ch in text) + '"'


def _model(title: str) -> str:
    return f"""model titled {_elab_string(title)}
import std
param half_period: uint16 = 500 range 10..5000 unit "ms" service rw
device led: DigitalOut(pin = "PB5")
dataflow Blink {{
    wave = SquareWave(half_period = half_period)
    wave.y -> led.level
}}
task main period 1 ms {{ run Blink }}
debug on uart0
modbus rtu on uart1
"""


def _title_in_the_program(tmp_path, title: str, name: str = "model.elab") -> bytes:
    built = build(write_model(tmp_path, _model(title), name=name), "host", tmp_path / "out")
    return built.executable.read_bytes()


def test_a_title_that_closes_a_comment_injects_nothing(tmp_path):
    title = "*/ int injected_by_title = 1; /*"
    program = _title_in_the_program(tmp_path, title)
    assert title.encode() in program
    symbols = subprocess.run(["nm", str(tmp_path / "out" / "titled")], capture_output=True, text=True).stdout
    assert "injected_by_title" not in symbols


@pytest.mark.parametrize("title", ["*/", "??/", "\u202e", "a\\", '"; int x = 1; "'])
def test_a_title_of_c_syntax_builds_and_keeps_its_bytes(tmp_path, title):
    assert title.encode() in _title_in_the_program(tmp_path, title)


TITLES = st.text(st.characters(codec="utf-8", exclude_characters="\0"), min_size=1, max_size=60).filter(
    lambda t: len(t.encode("utf-8")) <= 255)


@settings(max_examples=4, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(TITLES)
def test_any_title_builds_warning_free_and_keeps_its_bytes(tmp_path_factory, title):
    folder = tmp_path_factory.mktemp("title")
    assert title.encode("utf-8") in _title_in_the_program(folder, title)


def test_a_model_named_by_an_odd_file_name_builds(tmp_path):
    folder = tmp_path / "dir*"
    folder.mkdir()
    path = write_model(folder, _model("t").replace('model titled "t"\n', ""), name='we"ird??-/*.elab'.replace("/", ""))
    build(path, "host", tmp_path / "out")
