"""The VS Code extension's TextMate grammar (editors/vscode/syntaxes/,
written by tools/textmate_grammar.py from elab.lark): up to date with the
model language's grammar, and on every .elab in the repository it scopes
each token the language's own lexer finds as that lexer does: keywords as
keywords, numbers, units, strings and comments as such; mutated models
(tests/frontend/mutations.py, seeded) never make it fail."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from textmate import ROOT, lark_tokens, textmate_tokens

sys.path.insert(0, str(ROOT / "tools"))
sys.path.insert(0, str(ROOT / "tests" / "frontend"))
import textmate_grammar  # noqa: E402
from mutations import SeededChooser, mutate  # noqa: E402

ELAB_FILES = sorted(ROOT / p for p in subprocess.run(["git", "ls-files", "*.elab"], cwd=ROOT, capture_output=True,
                                                     text=True, check=True).stdout.split())


def test_the_committed_grammar_is_written_from_elab_lark():
    assert textmate_grammar.main(["--check"]) == 0


def test_every_keyword_of_the_lark_grammar_has_a_keyword_scope():
    """Each keyword, alone on a line, gets a keyword (or constant) scope;
    the units only after a number."""
    keywords = textmate_grammar.lark_keywords()
    units = {w for w, t in keywords.items() if t in textmate_grammar.UNIT_TERMINALS}
    words = sorted(set(keywords) - units)
    assert {"model", "dataflow", "chart", "transition", "min-buffer", "true", "and"} <= set(words)
    lines = words + [f"5 {u}" for u in sorted(units)]
    tokens = textmate_tokens(["\n".join(lines)])[0]
    for index, line in enumerate(lines):
        word = line.split()[-1]
        start = line.index(word)
        scopes = _scopes_at(tokens, index, start)
        assert _category(scopes) in ("keyword", "constant", "unit"), (line, scopes)
        assert any(t[0] == index and t[1] == start and t[2] == start + len(word) for t in tokens), (line, tokens)


def _scopes_at(tokens, line: int, column: int) -> list[str]:
    for t_line, start, end, scopes in tokens:
        if t_line == line and start <= column < end:
            return scopes
    return []


def _category(scopes: list[str]) -> str:
    """What a TextMate token is, from its innermost scope."""
    inner = scopes[-1] if scopes else ""
    for prefix, category in (("keyword.other.unit", "unit"), ("keyword", "keyword"), ("constant.numeric", "number"),
                             ("constant.language", "constant"), ("string", "string"), ("comment", "comment"),
                             ("constant.character.escape", "string"), ("support.type", "name"),
                             ("variable", "name"), ("punctuation.section.embedded", "inline-c"),
                             ("punctuation", "punctuation")):
        if inner.startswith(prefix):
            return category
    return "none"


def _lark_category(token) -> str:
    kind = token.type
    if kind in ("COMMENT", "BLOCK_COMMENT"):
        return "comment"
    if kind in ("INT", "REAL"):
        return "number"
    if kind in ("US", "MS", "SEC"):
        return "unit"
    if kind == "STRING":
        return "string"
    if kind == "C_CODE":
        return "inline-c"
    if kind == "NAME":
        return "name"
    if token.value in ("true", "false"):
        return "constant"
    if token.value[:1].isalpha():
        return "keyword"
    return "operator"


def test_every_elab_in_the_repository_is_scoped_as_the_language_lexes_it():
    assert len(ELAB_FILES) > 10
    texts = [p.read_text(encoding="utf-8") for p in ELAB_FILES]
    compared = 0
    for path, text, tokens in zip(ELAB_FILES, texts, textmate_tokens(texts)):
        lexed = lark_tokens(text)
        if lexed is None:
            continue
        compared += 1
        where = path.relative_to(ROOT)
        for token in lexed:
            expected = _lark_category(token)
            scopes = _scopes_at(tokens, token.line - 1, token.column - 1)
            got = _category(scopes)
            at = f"{where}:{token.line}:{token.column} {token.value!r}"
            assert got != "none", f"{at}: no scope"
            if expected == "name":
                # Keywords are contextual: a name spelled like one may look like one.
                assert got in ("name", "keyword", "constant", "unit"), f"{at}: {scopes}"
            elif expected == "operator":
                assert got in ("keyword", "punctuation"), f"{at}: {scopes}"
            else:
                assert got == expected, f"{at}: {expected}, TextMate: {scopes}"
        # And the other way: no comment, string or number where the lexer has none.
        starts = {(t.line - 1, t.column - 1): _lark_category(t) for t in lexed}
        for line, start, end, scopes in tokens:
            got = _category(scopes)
            if got in ("comment", "string", "number") and (line, start) not in starts:
                continued = any(s[-1] == scopes[-1] and (l, e) == (line, start) for l, _, e, s in tokens) \
                    or scopes[-1].startswith("comment.block") or got == "string"
                assert continued, f"{where}:{line + 1}:{start + 1}: {scopes} where the lexer has no {got}"
    assert compared > 10


def test_mutated_models_never_fail_the_grammar():
    """Seeded mutations of the examples: tokenizing never throws, every
    line gets tokens and every character a scope."""
    originals = [p.read_text(encoding="utf-8") for p in ELAB_FILES if p.parent.name == "examples"]
    texts = [mutate(originals[seed % len(originals)], SeededChooser(31_000 + seed)) for seed in range(300)]
    for text, tokens in zip(texts, textmate_tokens(texts)):
        lines = text.replace("\r\n", "\n").split("\n")
        for index, line in enumerate(lines):
            covered = sorted((s, e) for l, s, e, _ in tokens if l == index)
            assert covered or not line, (index, line)
            position = 0
            for start, end in covered:
                assert start == position, (index, line, covered)
                position = end
            assert position == len(line) or not line, (index, line, covered)
