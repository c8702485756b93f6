"""The DFA lexer builder behind editors/tree-sitter-elab/src/parser.c
(tools/tree_sitter_lexer.py): for each terminal of the model language, the
DFA built from its regular expression accepts exactly the texts Python's
own regex engine matches whole (the first match only, for a non-greedy
terminal), on texts drawn by hypothesis; and a DFA of several terminals
takes the longest match, ties going to the terminal that ranks first."""

from __future__ import annotations

import re
import sys

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tree_sitter_lang import ROOT

sys.path.insert(0, str(ROOT / "tools"))
import tree_sitter_grammar  # noqa: E402
from tree_sitter_lexer import LexerBuilder  # noqa: E402

GRAMMAR = tree_sitter_grammar.build_grammar()
PATTERNS = {name: (tree_sitter_grammar._c_code_regex() if name == "C_CODE" else term.pattern.to_regexp())
            for name, term in GRAMMAR.terminals.items() if term.pattern.type == "re"}
# Characters the terminals care about, and some they do not.
ALPHABET = "aZ_09xXbB.eE+-\"\\\n\t /*{}é"


def run(builder: LexerBuilder, start: int, text: str) -> str | None:
    """The terminal the DFA accepts after reading all of ``text``."""
    state = start
    for char in text:
        code = ord(char)
        moves = [target for ranges, target, skip in builder.states[state].moves
                 if not skip and any(lo <= code <= hi for lo, hi in ranges)]
        if not moves:
            return None
        state, = moves
    return builder.states[state].accept


def longest(builder: LexerBuilder, start: int, text: str) -> tuple[str, int] | None:
    """The token the DFA reads at the start of ``text``: (terminal, length)."""
    found, state = None, start
    for length in range(len(text) + 1):
        if builder.states[state].accept:
            found = builder.states[state].accept, length
        if length == len(text):
            break
        code = ord(text[length])
        moves = [t for ranges, t, skip in builder.states[state].moves
                 if not skip and any(a <= code <= b for a, b in ranges)]
        if not moves:
            break
        state, = moves
    return found


def python_accepts(pattern: str, text: str) -> bool:
    if not re.fullmatch(pattern, text):
        return False
    if "*?" in pattern:  # non-greedy: no shorter prefix may match
        return not any(re.fullmatch(pattern, text[:k]) for k in range(len(text)))
    return True


@pytest.fixture(scope="module")
def single():
    builder = LexerBuilder({n: (p, 0) for n, p in PATTERNS.items()}, {n: (0, i) for i, n in enumerate(PATTERNS)})
    return builder, {n: builder.add_mode([n], [], None) for n in PATTERNS}


def test_the_grammar_s_pattern_terminals_are_all_tested():
    assert {"NAME", "INT", "REAL", "STRING", "C_CODE", "COMMENT", "BLOCK_COMMENT", "WS"} <= set(PATTERNS)


@settings(max_examples=400, deadline=None, derandomize=True)
@given(name=st.sampled_from(sorted(PATTERNS)), text=st.text(ALPHABET, max_size=14))
def test_a_terminal_s_dfa_accepts_what_its_regex_matches(single, name, text):
    builder, starts = single
    assert (run(builder, starts[name], text) == name) == python_accepts(PATTERNS[name], text), (name, text)


@pytest.mark.parametrize("name, text", [
    ("NAME", "step_2"), ("INT", "0x1F"), ("INT", "0b101"), ("REAL", "1.5e-3"), ("REAL", "2e10"),
    ("STRING", '"a\\"b"'), ("COMMENT", "// x */"), ("BLOCK_COMMENT", "/* a\n* b */"),
    ("C_CODE", "{{ if (a) { b(); } }}"), ("C_CODE", "{{ a } b { c }}"), ("WS", " \t\n"),
])
def test_a_terminal_s_dfa_accepts_written_examples(single, name, text):
    builder, starts = single
    assert run(builder, starts[name], text) == name
    assert python_accepts(PATTERNS[name], text)


@settings(max_examples=300, deadline=None, derandomize=True)
@given(text=st.text("a0x.e5-/*\"{} ", min_size=1, max_size=12))
def test_several_terminals_take_the_longest_match(text):
    names = ["NAME", "INT", "REAL", "STRING", "COMMENT", "BLOCK_COMMENT", "DOTDOT", "MINUS", "SLASH", "STAR"]
    patterns = {n: (PATTERNS[n] if n in PATTERNS else re.escape(GRAMMAR.terminals[n].pattern.value), 0)
                for n in names}
    builder = LexerBuilder(patterns, {n: (0, i) for i, n in enumerate(names)})
    start = builder.add_mode(names, [], None)
    found = longest(builder, start, text)
    lengths = {n: max((k for k in range(1, len(text) + 1) if python_accepts(patterns[n][0], text[:k])), default=0)
               for n in names}
    best = max(lengths.values())
    if best == 0:
        assert found is None
    else:
        assert found == (min((n for n in names if lengths[n] == best), key=names.index), best)
