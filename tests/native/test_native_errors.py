"""`easylab build` failures: one clear line (`easylab: error: ...`) and a
non-zero exit status, never a Python traceback; a model the checker
rejects gives its diagnostics and exit status 1."""

from __future__ import annotations

import os
import re

import pytest

from native_testlib import DATA, ROOT, cli

BLINK = ROOT / "examples" / "blink.elab"
BOARDS = sorted(p.parent.name for p in (ROOT / "boards").glob("*/board.toml"))


def one_line_error(proc) -> str:
    assert proc.returncode != 0
    assert "Traceback" not in proc.stderr and "Traceback" not in proc.stdout, proc.stderr
    lines = proc.stderr.splitlines()
    assert len(lines) == 1, proc.stderr
    assert lines[0].startswith("easylab: error: "), lines[0]
    return lines[0]


def test_compiler_given_with_cc_is_missing(tmp_path):
    proc = cli("build", BLINK, "-o", tmp_path / "out", "--cc", "no-such-cc")
    line = one_line_error(proc)
    assert "'no-such-cc'" in line and "not installed" in line
    assert not (tmp_path / "out" / "blink").exists()


@pytest.mark.parametrize("board", BOARDS)
def test_board_compiler_missing_names_the_debian_package(board, tmp_path):
    """With no compiler on PATH, the compiler the board runs here (its own,
    or a proxy of one that does not run here) is reported with the Debian
    package that provides it. The model is the board's conformance blink
    (board.toml [conformance] model) where it has one."""
    from easylab.board.registry import load_board

    description = load_board(board).description
    cc = description.toolchain.cc
    model = description.raw.get("conformance", {}).get("model")
    empty = tmp_path / "bin"
    empty.mkdir()
    env = dict(os.environ, PATH=str(empty))
    line = one_line_error(cli("build", description.folder / model if model else BLINK, "--board", board, "-o",
                              tmp_path / "out", env=env))
    assert re.search(rf"'[\w.+-]+' of board '{board}' is not installed", line), line
    assert "(Debian package" in line  # "package: x" or "packages: x y"
    if cc == "gcc":
        assert line.endswith("(Debian package: gcc)")


def test_cross_compiler_missing_names_its_debian_package(tmp_path):
    empty = tmp_path / "bin"
    empty.mkdir()
    env = dict(os.environ, PATH=str(empty))
    line = one_line_error(cli("build", BLINK, "-o", tmp_path / "out", "--cc", "avr-gcc", env=env))
    assert "'avr-gcc'" in line and line.endswith("(Debian package: gcc-avr)")
    line = one_line_error(cli("build", BLINK, "-o", tmp_path / "out", "--cc", "sdcc", env=env))
    assert "'sdcc'" in line and line.endswith("(Debian package: sdcc)")


def test_output_folder_under_a_file(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder\n")
    line = one_line_error(cli("build", BLINK, "-o", blocker / "out"))
    assert "cannot write" in line and str(blocker / "out") in line


def test_output_folder_is_a_file(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder\n")
    line = one_line_error(cli("build", BLINK, "-o", blocker))
    assert "cannot write" in line and str(blocker) in line
    assert blocker.read_text() == "not a folder\n"


def test_output_folder_not_creatable(tmp_path):
    """A folder nobody can create, root included (procfs takes no new folders)."""
    line = one_line_error(cli("build", BLINK, "-o", "/proc/easylab-out"))
    assert "cannot write to /proc/easylab-out" in line


def test_output_files_not_writable(tmp_path):
    """The folder exists but model.c cannot be written (it is a folder)."""
    out = tmp_path / "out"
    (out / "model.c").mkdir(parents=True)
    line = one_line_error(cli("build", BLINK, "-o", out))
    assert "cannot write" in line


def test_unknown_board(tmp_path):
    line = one_line_error(cli("build", BLINK, "--board", "no-such-board", "-o", tmp_path / "out"))
    assert "no-such-board" in line and "host" in line


def test_missing_model_file(tmp_path):
    line = one_line_error(cli("build", tmp_path / "nothing.elab", "-o", tmp_path / "out"))
    assert "nothing.elab" in line


def test_model_rejected_by_the_checker(tmp_path):
    model = "bad_model.elab"  # run in data/: reported as given
    proc = cli("build", model, "-o", tmp_path / "out", cwd=DATA)
    assert proc.returncode == 1
    assert "Traceback" not in proc.stderr
    errors = [line for line in proc.stderr.splitlines() if ": error: " in line]
    assert errors == [f"{model}:6:5: error: 'level' is already declared as a var",
                      f"{model}:9:9: error: unknown actor type 'NoSuchActor'"], proc.stderr
    assert f"{model}:5:5: note: " in proc.stderr  # the first declaration
    assert proc.stdout == ""
    assert not (tmp_path / "out").exists()
