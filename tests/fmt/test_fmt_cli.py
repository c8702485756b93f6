"""`easylab fmt` on the command line: --check's status and the files it
names, rewriting in place, standard input to standard output, --diff, and
a file that does not parse (its error as file:line:col, the file untouched)."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from fmt_helpers import ROOT

MESSY = 'model m\nimport std\nvar   x:int16=1   // the count\nvar longer : bool\n\n\n\ndataflow D {\n  g=Const<int16>( value = 2 )\n    g.y->x\n}\ntask t period 10 ms {run D}\n'
TIDY = 'model m\nimport std\nvar x:      int16 = 1   // the count\nvar longer: bool\n\ndataflow D {\n    g = Const<int16>(value = 2)\n    g.y -> x\n}\ntask t period 10 ms { run D }\n'


def fmt(*args, cwd, stdin=None):
    return subprocess.run([sys.executable, "-m", "easylab", "fmt", *args], cwd=cwd, input=stdin,
                          capture_output=True, text=True)


@pytest.fixture
def files(tmp_path):
    (tmp_path / "messy.elab").write_text(MESSY)
    (tmp_path / "tidy.elab").write_text(TIDY)
    return tmp_path


def test_check_names_the_files_that_would_change_and_changes_nothing(files):
    proc = fmt("--check", "tidy.elab", "messy.elab", cwd=files)
    assert (proc.returncode, proc.stdout, proc.stderr) == (1, "messy.elab\n", "")
    assert (files / "messy.elab").read_text() == MESSY


def test_check_prints_nothing_when_every_file_is_canonical(files):
    proc = fmt("--check", "tidy.elab", cwd=files)
    assert (proc.returncode, proc.stdout, proc.stderr) == (0, "", "")


def test_files_are_rewritten_in_place_keeping_their_mode(files):
    os.chmod(files / "messy.elab", 0o640)
    proc = fmt("messy.elab", "tidy.elab", cwd=files)
    assert (proc.returncode, proc.stdout, proc.stderr) == (0, "", "")
    assert (files / "messy.elab").read_text() == TIDY
    assert os.stat(files / "messy.elab").st_mode & 0o777 == 0o640
    assert sorted(p.name for p in files.iterdir()) == ["messy.elab", "tidy.elab"]  # no temporary file left
    assert fmt("--check", "messy.elab", cwd=files).returncode == 0


@pytest.mark.parametrize("args", [(), ("-",)])
def test_standard_input_goes_to_standard_output(files, args):
    proc = fmt(*args, cwd=files, stdin=MESSY)
    assert (proc.returncode, proc.stdout, proc.stderr) == (0, TIDY, "")


def test_check_on_standard_input(files):
    assert fmt("--check", cwd=files, stdin=TIDY).returncode == 0
    proc = fmt("--check", "-", cwd=files, stdin=MESSY)
    assert (proc.returncode, proc.stdout) == (1, "<stdin>\n")


def test_diff_shows_the_changes_and_writes_nothing(files):
    proc = fmt("--diff", "messy.elab", cwd=files)
    assert proc.returncode == 0
    assert "--- messy.elab (before)\n+++ messy.elab (formatted)\n" in proc.stdout
    assert "\n-  g=Const<int16>( value = 2 )\n" in proc.stdout and "\n+    g = Const<int16>(value = 2)\n" in proc.stdout
    assert (files / "messy.elab").read_text() == MESSY
    assert fmt("--diff", "tidy.elab", cwd=files).stdout == ""


def test_a_file_that_does_not_parse_is_left_untouched(files):
    bad = "model m\nvar x: int16\ndataflow D {\n    x -> \n}\n"
    (files / "bad.elab").write_text(bad)
    proc = fmt("bad.elab", "messy.elab", cwd=files)
    assert proc.returncode == 1
    assert proc.stderr.startswith("bad.elab:5:1: error: ")
    assert (files / "bad.elab").read_text() == bad
    assert (files / "messy.elab").read_text() == TIDY  # the other files are still formatted


def test_an_unclosed_inline_c_block_is_a_parse_error(files):
    (files / "c.elab").write_text("actor type A() {\n    step {{ x = 1; }\n}\n")
    proc = fmt("--check", "c.elab", cwd=files)
    assert proc.returncode == 1 and proc.stderr.startswith("c.elab:2:10: error: inline C block")


def test_a_missing_file(files):
    proc = fmt("nowhere.elab", cwd=files)
    assert proc.returncode == 1 and proc.stderr == "easylab: error: nowhere.elab: No such file or directory\n"


def test_comments_and_inline_c_stay_as_written(files):
    text = ("/* a block\n     comment */\nactor type A() {\n    out y: int16\n"
            "        step {{\n  y = 1;   /* { */ // }\n    }}   // after C\n}\n")
    proc = fmt(cwd=files, stdin=text)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout == text.replace("        step", "    step").replace("}}   // after C", "}} // after C")
