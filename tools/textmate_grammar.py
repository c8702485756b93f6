#!/usr/bin/env python3
"""Writes editors/vscode/syntaxes/elab.tmLanguage.json, the TextMate grammar
of .elab files, from the model language's own grammar (elab.lark) and type
table, so the editor's keywords, units and types are the compiler's.

    python tools/textmate_grammar.py          # write the grammar
    python tools/textmate_grammar.py --check  # exit 1 if it is out of date

tests/editors/test_textmate_grammar.py checks that the committed file is
what this script writes.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OUTPUT = ROOT / "editors" / "vscode" / "syntaxes" / "elab.tmLanguage.json"

# Terminals the TextMate grammar scopes otherwise than as plain keywords:
# duration units after a number, the boolean literals, the logical operators.
UNIT_TERMINALS = ("US", "MS", "SEC")
CONSTANT_WORDS = ("true", "false")
LOGICAL_WORDS = ("and", "or", "not")


def lark_keywords() -> dict[str, str]:
    """Every keyword of elab.lark: its spelling -> its terminal's name
    (lark's own name for the anonymous ones, e.g. MODEL)."""
    import lark

    from easylab.frontend.grammar import grammar_text

    parser = lark.Lark(grammar_text(), parser="lalr", lexer="contextual")
    words = {}
    for term in parser.terminals:
        pattern = term.pattern
        if isinstance(pattern, lark.lexer.PatternStr) and re.fullmatch(r"[a-z][a-z-]*", pattern.value):
            words[pattern.value] = term.name
    return words


def type_names() -> list[str]:
    """The built-in value types' names (core/types.py)."""
    from easylab.core.types import ALL_TYPES

    return sorted(ALL_TYPES)


def _alternation(words) -> str:
    # Longest first, so that no word's prefix wins (`min-buffer` before `min`).
    return "|".join(re.escape(w) for w in sorted(words, key=lambda w: (-len(w), w)))


def _word(words) -> str:
    """Whole words that are not a path's later part (`a.step` is a name)."""
    return rf"(?<![\w.])(?:{_alternation(words)})(?![\w-])"


NUMBER = r"0[xX][0-9a-fA-F]+|0[bB][01]+|[0-9]+\.[0-9]+(?:[eE][-+]?[0-9]+)?|[0-9]+[eE][-+]?[0-9]+|[0-9]+"


def build() -> dict:
    """The TextMate grammar as a JSON-ready dict."""
    keywords = lark_keywords()
    units = sorted(w for w, t in keywords.items() if t in UNIT_TERMINALS)
    plain = sorted(w for w, t in keywords.items()
                   if t not in UNIT_TERMINALS and w not in CONSTANT_WORDS and w not in LOGICAL_WORDS)
    return {
        "$schema": "https://raw.githubusercontent.com/martinring/tmlanguage/master/tmlanguage.json",
        "name": "EasyLab model",
        "scopeName": "source.elab",
        "fileTypes": ["elab"],
        "comment": "Written by tools/textmate_grammar.py from generator/frontend/elab.lark: edit that, not this.",
        "patterns": [{"include": f"#{name}"} for name in
                     ("comments", "inline-c", "strings", "numbers", "constants", "logical", "keywords", "types",
                      "operators", "punctuation", "names")],
        "repository": {
            "comments": {"patterns": [
                {"name": "comment.line.double-slash.elab", "match": r"//.*$"},
                {"name": "comment.block.elab", "begin": r"/\*", "end": r"\*/"},
            ]},
            "inline-c": {
                "begin": r"\{\{", "end": r"\}\}",
                "beginCaptures": {"0": {"name": "punctuation.section.embedded.begin.elab"}},
                "endCaptures": {"0": {"name": "punctuation.section.embedded.end.elab"}},
                "contentName": "meta.embedded.block.c",
                "patterns": [{"include": "#c-braces"}, {"include": "source.c"}],
            },
            # Inline C runs to the `}}` that balances its `{{` (inline_c.py):
            # braces inside it nest.
            "c-braces": {"begin": r"\{", "end": r"\}",
                         "patterns": [{"include": "#c-braces"}, {"include": "source.c"}]},
            "strings": {"name": "string.quoted.double.elab", "begin": '"', "end": r'"|(?=$)',
                        "patterns": [{"name": "constant.character.escape.elab", "match": r"\\."}]},
            "numbers": {
                "match": rf"(?<!\w)({NUMBER})(?:\s*({_alternation(units)})(?!\w))?(?!\w)",
                "captures": {"1": {"name": "constant.numeric.elab"}, "2": {"name": "keyword.other.unit.elab"}},
            },
            "constants": {"name": "constant.language.boolean.elab", "match": _word(CONSTANT_WORDS)},
            "logical": {"name": "keyword.operator.logical.elab", "match": _word(LOGICAL_WORDS)},
            # No keyword stands right before `=` or `:` in the grammar: there the
            # word is a name (`AnalogIn(channel = 1)`, `out: bool`).
            "keywords": {"name": "keyword.other.elab", "match": _word(plain) + r"(?!\s*(?:=(?!=)|:))"},
            "types": {"name": "support.type.elab", "match": _word(type_names())},
            "operators": {"patterns": [
                {"name": "keyword.operator.arrow.elab", "match": "->"},
                {"name": "keyword.operator.range.elab", "match": r"\.\."},
                {"name": "keyword.operator.comparison.elab", "match": "==|!=|<=|>=|<|>"},
                {"name": "keyword.operator.assignment.elab", "match": "="},
                {"name": "keyword.operator.arithmetic.elab", "match": r"[-+*/%]"},
                {"name": "keyword.operator.address.elab", "match": "@"},
            ]},
            "punctuation": {"patterns": [
                {"name": "punctuation.separator.elab", "match": "[,:]"},
                {"name": "punctuation.accessor.elab", "match": r"\."},
                {"name": "punctuation.bracket.elab", "match": r"[{}()\[\]]"},
            ]},
            "names": {"name": "variable.other.elab", "match": r"[A-Za-z_][A-Za-z0-9_]*"},
        },
    }


def text() -> str:
    return json.dumps(build(), indent=2) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--check", action="store_true", help="exit 1 if the committed grammar is out of date")
    args = parser.parse_args(argv)
    if args.check:
        if not OUTPUT.is_file() or OUTPUT.read_text(encoding="utf-8") != text():
            print(f"{OUTPUT.relative_to(ROOT)} is out of date: run python tools/textmate_grammar.py", file=sys.stderr)
            return 1
        return 0
    OUTPUT.parent.mkdir(parents=True, exist_ok=True)
    OUTPUT.write_text(text(), encoding="utf-8")
    print(OUTPUT.relative_to(ROOT))
    return 0


if __name__ == "__main__":
    sys.exit(main())
