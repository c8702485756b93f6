"""The mutation campaign (mutation_campaign.py) at a tiny size, so that it
does not rot: its own verdicts, and no finding on its first mutants."""

from __future__ import annotations

import json

import pytest

import mutation_campaign
from mutations import SeededChooser, mutate


def test_a_seed_gives_the_same_mutant():
    text = mutation_campaign.SEEDS[0].read_text(encoding="utf-8")
    assert mutate(text, SeededChooser(5)) == mutate(text, SeededChooser(5))
    assert mutate(text, SeededChooser(5)) != text


def test_a_small_campaign_checks_builds_and_finds_nothing(tmp_path):
    assert mutation_campaign.main(["-n", "24", "--jobs", "1", "--out", str(tmp_path)]) == 0
    tally = json.loads((tmp_path / "summary.json").read_text())["tally"]
    assert sum(tally.values()) == 24 and "finding" not in tally
    assert tally.get("refused", 0) > 0


@pytest.mark.parametrize("state, name", [("sum", "sum"), ("n", "n")])  # a body of several lines, of one line
def test_an_actor_body_using_a_deleted_state_is_the_users_c(state, name, tmp_path):
    """A mutant without a `state` whose actor body still uses it: the
    checker accepts it (it does not read C), gcc refuses it on a line of the
    model's own C: the campaign counts it as the user's C, not a finding;
    an error on a generated line stays a finding."""
    import subprocess
    import sys

    original = (mutation_campaign.ROOT / "examples" / "cd_to_dat.elab").read_text(encoding="utf-8")
    text = original.replace(f"    state {state}: uint32\n", "", 1)
    assert text != original
    model = tmp_path / "cd_to_dat.elab"
    model.write_text(text, encoding="utf-8")
    proc = subprocess.run([sys.executable, "-m", "easylab", "build", str(model), "--board", "host", "-o",
                           str(tmp_path / "host")], capture_output=True, text=True, timeout=300)
    assert proc.returncode != 0, proc.stderr
    assert any(f"{name}{quote} undeclared" in proc.stderr for quote in ("’", "'")), proc.stderr
    assert mutation_campaign.errors_in_user_c(proc.stderr, text)
    generated_line = f"{tmp_path / 'host' / 'model.c'}:1:1: error: something of ours\n"
    assert not mutation_campaign.errors_in_user_c(generated_line, text)
    assert not mutation_campaign.errors_in_user_c("no error line at all", text)
