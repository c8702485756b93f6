"""The parser's tables cached on disk (frontend/parser.py, _cached_lark):
the same trees as a parser built from the grammar, a cache file written
whole, and a damaged or unwritable cache no error."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import lark

from easylab.frontend.grammar import grammar_text
from easylab.frontend.inline_c import blank_inline_c
from easylab.frontend.parser import _cached_lark

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = sorted((ROOT / "examples").rglob("*.elab"))


def _options() -> dict:
    return dict(parser="lalr", lexer="contextual", keep_all_tokens=True, maybe_placeholders=False)


def test_the_cached_tables_parse_as_the_grammar_does(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    built = lark.Lark(grammar_text(), **_options())
    writes = _cached_lark(grammar_text(), _options())
    [cache] = (tmp_path / "easylab").glob("grammar-*.lark")
    reads = _cached_lark(grammar_text(), _options())
    assert list((tmp_path / "easylab").iterdir()) == [cache]  # no temporary file left
    for example in EXAMPLES:
        text, _ = blank_inline_c(example.read_text(encoding="utf-8"), str(example))
        assert writes.parse(text) == built.parse(text) == reads.parse(text), example


def _check(cache_home: Path) -> subprocess.CompletedProcess:
    env = {**os.environ, "XDG_CACHE_HOME": str(cache_home)}
    return subprocess.run([sys.executable, "-m", "easylab", "check", str(ROOT / "examples" / "blink.elab")],
                          capture_output=True, text=True, env=env, timeout=120)


def test_a_damaged_or_unwritable_cache_is_no_error(tmp_path):
    first = _check(tmp_path)
    assert first.returncode == 0 and first.stderr == "", first.stderr
    [cache] = (tmp_path / "easylab").glob("grammar-*.lark")
    cache.write_bytes(cache.read_bytes()[:100])  # damaged
    damaged = _check(tmp_path)
    assert (damaged.returncode, damaged.stdout, damaged.stderr) == (0, first.stdout, "")
    blocked = tmp_path / "file"
    blocked.write_text("not a folder")
    unwritable = _check(blocked)
    assert (unwritable.returncode, unwritable.stdout, unwritable.stderr) == (0, first.stdout, "")
