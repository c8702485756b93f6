"""`easylab analyze` and the SDF checks of model dataflows, end to end."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SDF3 = ROOT / "tests" / "sdf" / "data" / "cd2dat.xml"

CD2DAT_ELAB = """\
model cd2dat_six
actor type Src() {
    out y: uint32
    state n: uint32
    step {{ n = n + 1u; y = n; }}
}
actor type Stage(p: uint8, c: uint8) {
    in  x: uint32 rate c
    out y: uint32 rate p
    state acc: uint32
    step {{ uint8_t i; for (i = 0; i < c; i++) acc += x[i]; for (i = 0; i < p; i++) y[i] = acc; }}
}
actor type Sink() {
    in x: uint32
    out y: uint32
    step {{ y = x; }}
}
dataflow Convert {
    A = Src()
    B = Stage(p = 2, c = 1)
    C = Stage(p = 2, c = 3)
    D = Stage(p = 8, c = 7)
    E = Stage(p = 5, c = 7)
    F = Sink()
    A.y -> B.x
    B.y -> C.x
    C.y -> D.x
    D.y -> E.x
    E.y -> F.x
}
task t period 10 ms { run Convert }
"""


def easylab(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "easylab", *map(str, args)], capture_output=True, text=True,
                          cwd=cwd, timeout=300)


def only(result):
    assert result.returncode == 0, result.stderr
    (df,) = json.loads(result.stdout)["dataflows"]
    return df


@pytest.fixture()
def six(tmp_path):
    path = tmp_path / "cd2dat.elab"
    path.write_text(CD2DAT_ELAB)
    return path


def test_cd_to_dat_model_and_sdf3_agree(six):
    for target in (six, SDF3):
        sas = only(easylab("analyze", target, "--json"))
        assert list(sas["repetitions"].values()) == [147, 147, 98, 28, 32, 160]
        assert sas["buffer_total"] == 264
        assert sas["sas_lower_bound"] == 82
        assert sas["edge_lower_bound"] == 32
        minbuf = only(easylab("analyze", target, "--json", "--schedule", "min-buffer"))
        assert minbuf["buffer_total"] == 32


def test_the_shipped_example_adds_one_edge_of_160_tokens():
    sas = only(easylab("analyze", ROOT / "examples" / "cd_to_dat.elab", "--json"))
    assert sas["repetitions"] == {"src": 147, "b": 147, "c": 98, "d": 28, "e": 32, "f": 160, "sum": 1}
    assert (sas["buffer_total"], sas["sas_lower_bound"], sas["edge_lower_bound"]) == (264 + 160, 82 + 160, 32 + 160)
    minbuf = only(easylab("analyze", ROOT / "examples" / "cd_to_dat.elab", "--json", "--schedule", "min-buffer"))
    assert minbuf["buffer_total"] == 32 + 160


def test_the_model_chooses_its_schedule(six, tmp_path):
    path = tmp_path / "chosen.elab"
    path.write_text(six.read_text().replace("dataflow Convert {", "dataflow Convert schedule min-buffer {"))
    assert only(easylab("analyze", path, "--json"))["buffer_total"] == 32
    assert only(easylab("analyze", path, "--json", "--schedule", "sas"))["buffer_total"] == 264


def test_text_report_and_dataflow_selection(six):
    out = easylab("analyze", six, "--dataflow", "Convert")
    assert out.returncode == 0
    assert "repetitions: A=147, B=147, C=98, D=28, E=32, F=160" in out.stdout
    assert "buffer total: 264 tokens" in out.stdout
    missing = easylab("analyze", six, "--dataflow", "Nope")
    assert missing.returncode == 1
    assert "has no dataflow 'Nope' (its dataflows: Convert)" in missing.stderr


def check_errors(tmp_path, text):
    path = tmp_path / "m.elab"
    path.write_text(text)
    out = easylab("check", path.name, cwd=tmp_path)
    assert out.returncode == 1
    assert "Traceback" not in out.stderr
    return out.stderr


RATES = """\
model rates
actor type Two() {
    in x: int16 rate 2
    out y: int16
    step {{ y = x[0]; }}
}
actor type Dup() {
    in x: int16
    out y: int16 rate 2
    step {{ y[0] = x; y[1] = x; }}
}
var v: int16
var w: int16
dataflow Loop {
    a = Two()
    b = Dup()
    a.y -> b.x
    b.y -> a.x
}
dataflow Bad {
    c = Two()
    v -> c.x
    c.y -> w
}
task t period 10 ms { run Loop run Bad }
"""


def test_deadlock_and_external_rate_errors_point_at_edges(tmp_path):
    err = check_errors(tmp_path, RATES)
    assert ("m.elab:17:5: error: dataflow 'Loop' deadlocks: the cycle through 'a.y -> b.x' lacks initial "
            "tokens; it needs") in err
    assert "hint: add initial tokens: a.y -> b.x delay" in err
    assert ("m.elab:22:5: error: 'v' gives 1 token per activation (a var), but dataflow 'Bad' consumes 2 per "
            "iteration through this edge") in err


INCONSISTENT = """\
model inconsistent
actor type P(n: uint8) {
    in x: int16
    out y: int16 rate n
    step {{ uint8_t i; for (i = 0; i < n; i++) y[i] = x; }}
}
dataflow D {
    a = P(n = 2)
    b = P(n = 1)
    a.y -> b.x
    b.y -> a.x delay 4
}
task t period 10 ms { run D }
"""


def test_inconsistent_rates_name_the_cycle(tmp_path):
    err = check_errors(tmp_path, INCONSISTENT)
    assert "error: dataflow 'D' has inconsistent rates" in err
    assert "a.y -> b.x" in err and "b.y -> a.x" in err


CHANNEL = """\
model chan
actor type Id() {
    in x: int16
    out y: int16
    step {{ y = x; }}
}
actor type Sum(n: uint8) {
    in x: int16 rate n
    out y: int16
    step {{ uint8_t i; y = 0; for (i = 0; i < n; i++) y = (int16_t)(y + x[i]); }}
}
var a: int16
var s: int16
channel c: int16 delay 2
dataflow Fast {
    i = Id()
    a -> i.x
    i.y -> c
}
dataflow Slow {
    m = Sum(n = 10)
    c -> m.x
    m.y -> s
}
task fast period 1 ms { run Fast }
task slow period 10 ms { run Slow }
"""


def test_a_channel_that_runs_dry_says_how_many_tokens_it_needs(tmp_path):
    err = check_errors(tmp_path, CHANNEL)
    assert "error: channel 'c' runs dry" in err
    assert "hint: declare it with: delay 10" in err


def test_a_channel_that_does_not_balance(tmp_path):
    err = check_errors(tmp_path, CHANNEL.replace("task slow period 10 ms", "task slow period 20 ms"))
    assert ("channel 'c' does not balance: task 'fast' puts 1 token(s) in every 1 ms, task 'slow' takes 10 "
            "every 20 ms") in err


def test_sdf3_errors_are_one_line(tmp_path):
    bad = tmp_path / "bad.xml"
    bad.write_text("<sdf3 type='sdf'><applicationGraph>")
    out = easylab("analyze", bad)
    assert out.returncode == 1
    assert out.stderr.startswith(f"{bad}: error:")
    assert "Traceback" not in out.stderr


WCET = """\
model wcet
var a: int16
var b: int16
dataflow A {
    a -> b
}
dataflow B {
    b -> a
}
task fast period 10 ms wcet 6 ms { run A }
task slow period 20 ms wcet 9 ms { run B }
"""


def test_wcet_overload_is_not_schedulable(tmp_path):
    err = check_errors(tmp_path, WCET)  # 6/10 + 9/20 = 105 %
    assert "the tasks' wcet add up to 105% of the processor: not schedulable" in err


def test_wcet_deadline_miss_names_the_task(tmp_path):
    # Non-preemptive: the slow job (0..2 fast, 2..12 slow) blocks the fast
    # job released at 10 ms until 12 ms; it ends at 14 ms, after 13 ms.
    text = WCET.replace("wcet 6 ms", "deadline 3 ms wcet 2 ms").replace("wcet 9 ms", "wcet 10 ms")
    err = check_errors(tmp_path, text)
    assert "task 'fast' can miss its deadline" in err


def test_wcet_that_fits_is_accepted(tmp_path):
    path = tmp_path / "ok.elab"
    path.write_text(WCET.replace("wcet 9 ms", "wcet 7 ms"))
    assert easylab("check", path).returncode == 0
