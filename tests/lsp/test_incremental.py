"""The server's parser re-parses only the chunks an edit changed, and
gives exactly what parsing the whole text gives: the same module (spans
included) or the same syntax error, for edits nobody wrote by hand."""

from __future__ import annotations

import sys
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from lsp_helpers import EXAMPLES, ROOT
from mutations import HypothesisChooser, mutate

from easylab.core.source import ModelError
from easylab.frontend.parser import parse_text
from easylab.lsp.incremental import ChunkedParser, chunks

sys.path.insert(0, str(ROOT / "bench"))
from bench_frontend import generate_model  # noqa: E402

SEEDS = [p.read_text(encoding="utf-8") for p in EXAMPLES] + [generate_model(120)]


def _outcome(parse, text: str):
    try:
        return parse(text, "m.elab")
    except ModelError as err:
        return [(d.span, d.message) for d in err.diagnostics]


def test_chunks_cover_the_text_and_count_lines():
    text = SEEDS[-1]
    parts = chunks(text)
    assert "".join(piece for _, piece in parts) == text
    for line, piece in parts:
        assert text.split("\n")[line].startswith(piece.split("\n")[0])


@settings(max_examples=150, deadline=None, derandomize=True, suppress_health_check=list(HealthCheck))
@given(st.data())
def test_an_edit_parses_as_the_whole_text_does(data):
    parser = ChunkedParser()
    original = data.draw(st.sampled_from(SEEDS))
    assert _outcome(parser, original) == _outcome(parse_text, original)
    for _ in range(2):  # edits after edits: the cache must never leak an old chunk
        text = mutate(original, HypothesisChooser(data.draw))
        assert _outcome(parser, text) == _outcome(parse_text, text)


def test_an_edit_inside_one_declaration_parses_that_chunk_only():
    parser = ChunkedParser()
    text = SEEDS[-1]
    parser(text, "big.elab")
    before = parser.chunks_parsed
    edited = text.replace("LowPass<int16>(alpha = 300)", "LowPass<int16>(alpha = 301)", 1)
    assert parser(edited, "big.elab") == parse_text(edited, "big.elab")
    assert parser.chunks_parsed == before + 1
