"""The campaign's ledger (crosscheck.py --ledger): results accumulate over
runs, a seed already compared is not run again, a finding is, and the
tally counts each seed's latest result once."""

from __future__ import annotations

import json

from crosscheck import Ledger, campaign, generator_digest, ledger_tally, main, read_ledger
from modelgen import Options


def test_a_second_run_skips_what_the_first_compared(tmp_path, capsys):
    ledger = tmp_path / "ledger.jsonl"
    campaign(range(7, 9), ["host"], tmp_path / "a", 2, Options(), Ledger(ledger))
    first = read_ledger(ledger)
    assert [(e["seed"], e["mode"], e["verdict"]) for e in first] == [
        (7, "local", "reference"), (7, "host", "equal"), (8, "local", "reference"), (8, "host", "equal")]
    assert {e["generator"] for e in first} == {generator_digest()}
    summary = campaign(range(7, 10), ["host"], tmp_path / "b", 2, Options(), Ledger(ledger))
    assert summary["tally"]["host"] == {"equal": 1}  # seed 9 only
    assert [e["seed"] for e in read_ledger(ledger) if e["mode"] == "host"] == [7, 8, 9]
    assert main(["--tally", str(ledger)]) == 0
    assert "host         equal 3" in capsys.readouterr().out


def test_findings_run_again_and_count_as_their_latest_result(tmp_path):
    ledger = tmp_path / "ledger.jsonl"
    digest = generator_digest()
    rows = [{"seed": 1, "part": "p", "mode": "pic18", "verdict": "differs", "commit": "a", "generator": digest},
            {"seed": 2, "part": "p", "mode": "pic18", "verdict": "skip", "commit": "a", "generator": digest},
            {"seed": 1, "part": "p", "mode": "pic18", "verdict": "equal", "commit": "b", "generator": digest},
            {"seed": 3, "part": "p", "mode": "pic18", "verdict": "equal", "commit": "a", "generator": "other"}]
    ledger.write_text("".join(json.dumps(r) + "\n" for r in rows))
    assert dict(ledger_tally(read_ledger(ledger))["pic18"]) == {"equal": 1, "skip": 1}  # this generator's
    assert dict(ledger_tally(read_ledger(ledger), "other")["pic18"]) == {"equal": 1}
    ledger.write_text("".join(json.dumps(r) + "\n" for r in rows[:2] + rows[3:]))
    book = Ledger(ledger)
    assert not book.done(1, "pic18")  # a finding: run again
    assert book.done(2, "pic18")
    assert not book.done(3, "pic18")  # another generator's seed 3 is another model
