"""Mutated examples never crash the front end.

Each case deletes, duplicates, swaps or replaces tokens and lines of an
example (or of tests/frontend/models/all_features.elab), or inserts
punctuation and keywords, then checks the result: either the model
is accepted, or every diagnostic points inside the file and the report
renders. Any other exception is a bug of the front end. The runs are
derandomized (the same cases on every machine) and bounded in number.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from easylab.pipeline import check_file
from mutations import HypothesisChooser, mutate

ROOT = Path(__file__).resolve().parents[2]
# The examples, and a model with every construct of the language once.
SEEDS = [*sorted((ROOT / "examples").glob("*.elab")), ROOT / "examples" / "vision_line" / "vision_line.elab",
         Path(__file__).parent / "models" / "all_features.elab"]
TOTAL_CASES = 3000


@st.composite
def mutated(draw, text: str) -> str:
    return mutate(text, HypothesisChooser(draw))


def _check_never_crashes(path: Path, text: str) -> None:
    path.write_text(text, encoding="utf-8")
    result = check_file(path)  # any exception here fails the test
    diagnostics = result.diagnostics.sorted()
    assert (result.model is None) == result.diagnostics.has_errors
    # Files are read with universal newlines (a lone '\r' ends a line too); the
    # lexer then counts lines at '\n' only (not at '\f' or '\u2028').
    own_lines = text.replace("\r\n", "\n").replace("\r", "\n").split("\n")
    for d in diagnostics:
        for span in (d.span, *(n.span for n in d.notes)):
            assert span.line >= 1 and span.column >= 1, (d.message, span)
            if Path(span.file).resolve() == path.resolve():
                assert span.line <= len(own_lines), (d.message, span)
        assert d.message
        if Path(d.span.file).resolve() == path.resolve():  # the excerpt quotes the right line
            shown = own_lines[d.span.line - 1].expandtabs(1)
            excerpt = d.render(result.sources).split("\n")[1 + d.message.count("\n")]
            assert excerpt == f"{d.span.line:5d} | {shown}", d.message
    report = result.report()
    assert isinstance(report, str)
    if diagnostics:
        assert report.startswith(f"{diagnostics[0].span}: error: ")


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    return tmp_path_factory.mktemp("mutations")


@pytest.mark.parametrize("seed", SEEDS, ids=lambda p: p.stem)
def test_mutated_example_never_crashes(seed, workdir):
    text = seed.read_text(encoding="utf-8")
    path = workdir / seed.name

    @settings(max_examples=TOTAL_CASES // len(SEEDS), deadline=None, derandomize=True, database=None,
              suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
    @given(mutated(text))
    def run(mutant):
        _check_never_crashes(path, mutant)

    run()


@pytest.mark.parametrize("text", [
    "", "\n", "// only a comment", "/*", "{{", "}}", '"', "model", "import", "import std\nimport std\n",
    "model m\nmodel m\n", "\ufeffvar x: int8\n", "var x: int8\r\nvar y: int8\r\n", "\t\tvar\tx:\tint8",
    "var a: int8\r\n// \f \u2028 \x0b\nvar b: int8 = y\n", "var x: int8 =\n\n\n",
    "x" * 10000, "(" * 5000, "var x: int8 = " + "(" * 2000 + "1" + ")" * 2000,
    "var x: int8 = " + "-" * 3000 + "1", "var x: int8 = 1" + " + 1" * 3000,
    "chart C { " + " ".join(f"step S{i} {{ }}" for i in range(300)) + " }",
])
def test_odd_files_never_crash(text, workdir):
    _check_never_crashes(workdir / "odd.elab", text)
