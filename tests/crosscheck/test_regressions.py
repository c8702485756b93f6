"""Every model kept from a back-to-back finding (regressions/*.elab, each
with the defect it found in its first comment) gives local execution's
trace in every mode: built and run as the campaign runs it. A model's
``// modes:`` line narrows the modes (pins of one part); by default it runs
in all but the ATmega328P's."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from crosscheck import Case, compare
from modes import MODES

HERE = Path(__file__).resolve().parent
MODELS = sorted((HERE / "regressions").glob("*.elab"))
DEFAULT_MODES = [m for m in MODES if m not in ("local", "avr328")]
DURATION_MS = 120


def modes_of(model: Path) -> list[str]:
    found = re.search(r"^// modes: (.+)$", model.read_text(), re.M)
    return found.group(1).split() if found else DEFAULT_MODES


CASES = [pytest.param(model, mode, id=f"{model.stem}-{mode}") for model in MODELS for mode in modes_of(model)]


def test_every_kept_model_has_its_stimulus():
    assert MODELS, "no regression models"
    for model in MODELS:
        assert model.with_suffix(".stimulus.csv").is_file(), model
        assert model.read_text().startswith("// "), f"{model.name}: say which defect it found, first"


@pytest.mark.parametrize("model, mode", CASES)
def test_kept_model_gives_local_executions_trace(model, mode, tmp_path):
    case = Case(model.stem, model, model.with_suffix(".stimulus.csv"), DURATION_MS)
    results = compare(case, tmp_path, [mode])
    assert results["local"][0] == "reference", results["local"][1]
    verdict, detail = results[mode]
    assert verdict == "equal", f"{model.name} in {mode}: {verdict}\n{detail}"
