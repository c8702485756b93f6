"""Every model of the repository is in the canonical layout (`easylab fmt
--check` passes), formatting is idempotent, and the layout is the
formatter's alone: any shuffle of a model's blanks formats back to the
same text, with the same IR."""

from __future__ import annotations

import random
import subprocess
import sys

import pytest

from fmt_helpers import ROOT, comments, ir_or_errors, repository_models, shuffle_whitespace

from easylab.frontend.format import format_text

MODELS = repository_models()


def test_the_repository_has_its_models():
    names = {p.relative_to(ROOT).as_posix() for p in MODELS}
    assert {"examples/blink.elab", "generator/stdlib/std.elab", "tests/frontend/models/all_features.elab"} <= names
    assert len(MODELS) > 40


def test_fmt_check_passes_on_every_model():
    proc = subprocess.run([sys.executable, "-m", "easylab", "fmt", "--check", *map(str, MODELS)],
                          cwd=ROOT, capture_output=True, text=True)
    assert (proc.returncode, proc.stdout, proc.stderr) == (0, "", "")


@pytest.mark.parametrize("path", MODELS, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_formatting_twice_changes_nothing_more(path):
    once = format_text(path.read_text(encoding="utf-8"), str(path))
    assert format_text(once, str(path)) == once


@pytest.mark.parametrize("path", MODELS, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_a_shuffled_layout_formats_back_with_the_same_meaning(path):
    text = path.read_text(encoding="utf-8")
    shuffled = shuffle_whitespace(text, random.Random(path.name))
    assert shuffled != text
    formatted = format_text(shuffled, str(path))
    assert formatted == text
    assert comments(formatted) == comments(shuffled)
    assert ir_or_errors(path, shuffled) == ir_or_errors(path, text)
