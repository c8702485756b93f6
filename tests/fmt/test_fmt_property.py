"""Formatting models nobody wrote by hand: mutated examples (the front
end's mutations, drawn by hypothesis) and the back-to-back tests' random
models, their blanks shuffled. For every text that parses, the formatted
text parses to the same model (the same IR, or the same errors), keeps
every comment, and formatting it again changes nothing."""

from __future__ import annotations

import random

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fmt_helpers import ROOT, comments, ir_or_errors, shuffle_whitespace
from modelgen import generate
from mutations import HypothesisChooser, mutate

from easylab.core.source import ModelError
from easylab.frontend.format import format_text
from easylab.frontend.parser import parse_text

SEEDS = [*sorted((ROOT / "examples").glob("*.elab")), ROOT / "examples" / "vision_line" / "vision_line.elab",
         ROOT / "tests" / "frontend" / "models" / "all_features.elab"]


def assert_formats_faithfully(path, text: str) -> bool:
    """The formatter's promises on ``text`` (read as the file ``path``);
    whether the text parsed at all."""
    try:
        parse_text(text, str(path))
    except ModelError:
        return False
    formatted = format_text(text, str(path))
    assert format_text(formatted, str(path)) == formatted
    assert comments(formatted) == comments(text)
    assert ir_or_errors(path, formatted) == ir_or_errors(path, text)
    return True


@settings(max_examples=150, deadline=None, derandomize=True, suppress_health_check=list(HealthCheck))
@given(st.data())
def test_mutated_examples_format_faithfully(data):
    path = data.draw(st.sampled_from(SEEDS))
    text = mutate(path.read_text(encoding="utf-8"), HypothesisChooser(data.draw))
    text = shuffle_whitespace(text, random.Random(data.draw(st.integers(0, 2**32))))
    assert_formats_faithfully(path, text)


@pytest.mark.parametrize("seed", range(12))
def test_random_models_format_faithfully(tmp_path, seed):
    model = generate(1000 + seed)
    path = tmp_path / f"{model.name}.elab"
    assert assert_formats_faithfully(path, model.text)
    shuffled = shuffle_whitespace(model.text, random.Random(seed))
    assert assert_formats_faithfully(path, shuffled)
    assert format_text(shuffled, str(path)) == format_text(model.text, str(path))
    assert ir_or_errors(path, model.text).startswith("{")  # the generator's models are good ones
