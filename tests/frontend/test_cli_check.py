"""`easylab check`: compiler-style diagnostics for bad models, one clear
line for files that are not models, never a traceback."""

from __future__ import annotations

from textwrap import dedent

BAD = dedent("""\
    import std
    var temperature: int16
    dataflow D {
        c = Const<int16>(value = 1)
        c.y -> temprature
    }
    task t period 10 { run D }
    """)


def test_bad_model_prints_location_line_caret_and_hint(cli, tmp_path):
    (tmp_path / "bad.elab").write_text(BAD)
    proc = cli("check", "bad.elab", cwd=tmp_path)
    assert proc.returncode == 1
    assert proc.stdout == ""
    assert proc.stderr == dedent("""\
        bad.elab:5:12: error: unknown name 'temprature' in dataflow 'D'
            5 |     c.y -> temprature
                           ^~~~~~~~~~
          hint: did you mean 'temperature'?
        bad.elab:7:15: error: the period of task 't' is a 'time': write a duration such as '10 ms'
            7 | task t period 10 { run D }
                              ^~
        bad.elab: 2 errors
        """)


def test_syntax_error_and_note_rendering(cli, tmp_path):
    (tmp_path / "m.elab").write_text("var x: int8\nvar x: int16\nvar y int8\n")
    proc = cli("check", tmp_path / "m.elab")
    assert proc.returncode == 1
    first = proc.stderr.splitlines()[0]
    assert first == f"{tmp_path / 'm.elab'}:3:7: error: unexpected 'int8': a declaration needs ':' and a type, " \
                    "as in 'var speed: int16'"
    assert proc.stderr.splitlines()[1:3] == ["    3 | var y int8", "              ^~~~"]
    assert "Traceback" not in proc.stderr

    (tmp_path / "m.elab").write_text("var x: int8\nvar x: int16\n")
    proc = cli("check", "m.elab", cwd=tmp_path)
    assert proc.returncode == 1
    assert proc.stderr == dedent("""\
        m.elab:2:5: error: 'x' is already declared as a var
            2 | var x: int16
                    ^
          hint: give one of them another name
        m.elab:1:5: note: 'x' is first declared here
            1 | var x: int8
                    ^
        m.elab: 1 error
        """)


def test_good_and_bad_files_together_exit_1(cli, tmp_path):
    (tmp_path / "bad.elab").write_text(BAD)
    (tmp_path / "good.elab").write_text("var x: int8\n")
    proc = cli("check", "good.elab", "bad.elab", cwd=tmp_path)
    assert proc.returncode == 1
    assert proc.stdout.startswith("good.elab: ok")
    assert "bad.elab:5:12: error:" in proc.stderr


def _one_error_line(proc) -> str:
    assert proc.returncode == 1
    assert "Traceback" not in proc.stderr
    lines = proc.stderr.splitlines()
    assert len(lines) == 1, proc.stderr
    assert lines[0].startswith("easylab: error: ")
    return lines[0]


def test_missing_file(cli, tmp_path):
    line = _one_error_line(cli("check", tmp_path / "nope.elab"))
    assert line == f"easylab: error: {tmp_path / 'nope.elab'}: no such file"


def test_directory(cli, tmp_path):
    line = _one_error_line(cli("check", tmp_path))
    assert line == f"easylab: error: {tmp_path}: is a directory, not a model file"


def test_binary_files(cli, tmp_path):
    (tmp_path / "random.elab").write_bytes(bytes(range(256)) * 4)
    line = _one_error_line(cli("check", tmp_path / "random.elab"))
    assert line == f"easylab: error: {tmp_path / 'random.elab'}: not a UTF-8 text file"
    (tmp_path / "zeros.elab").write_bytes(b"var x: int8\n" + bytes(64))  # valid UTF-8, but binary
    line = _one_error_line(cli("check", tmp_path / "zeros.elab"))
    assert line == f"easylab: error: {tmp_path / 'zeros.elab'}: not a UTF-8 text file"


def test_unreadable_import_is_a_diagnostic(cli, tmp_path):
    (tmp_path / "lib.elab").write_bytes(b"\xff\xfe\x00")
    (tmp_path / "m.elab").write_text('import "lib.elab"\n')
    proc = cli("check", "m.elab", cwd=tmp_path)
    assert proc.returncode == 1
    assert proc.stderr.startswith("m.elab:1:1: error: cannot read imported file 'lib.elab': ")
    assert "Traceback" not in proc.stderr
