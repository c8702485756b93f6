"""The mutation campaign (mutation_campaign.py) at a tiny size, so that it
does not rot: its own verdicts, and no finding on its first mutants."""

from __future__ import annotations

import json

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
