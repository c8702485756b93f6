"""The grammar itself: conflict-free LALR(1) in Lark's strict mode, with
contextual keywords, and the parser's table of common mistakes still
matching the grammar."""

from __future__ import annotations

from pathlib import Path

import interegular  # noqa: F401  (strict mode needs it to look for terminal collisions)
import lark
import pytest

from easylab.frontend import parser as P
from easylab.frontend import syntax_errors as E
from easylab.frontend.grammar import grammar_text
from easylab.frontend.loader import library_path
from easylab.core.source import ModelError

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("lexer", ["basic", "contextual"])
def test_grammar_is_strict_lalr(lexer):
    """No shift/reduce or reduce/reduce conflict, no two terminals that can
    match the same text (strict mode raises GrammarError or LexError)."""
    lark.Lark(grammar_text(), parser="lalr", lexer=lexer, strict=True)


def test_strict_mode_really_looks_for_collisions():
    colliding = grammar_text() + '\nFOO_NAME: /f[a-z]+/\nstart2: FOO_NAME\n'
    with pytest.raises(lark.exceptions.LexError, match="Collision"):
        lark.Lark(colliding, parser="lalr", lexer="basic", strict=True, start=["start", "start2"])
    conflicting = grammar_text().replace("?sum_expr: product | sum_expr (PLUS | MINUS) product -> binary",
                                            "?sum_expr: product | sum_expr (PLUS | MINUS) sum_expr -> binary")
    assert conflicting != grammar_text()
    with pytest.raises(lark.exceptions.GrammarError, match="conflict"):
        lark.Lark(conflicting, parser="lalr", strict=True)


@pytest.mark.parametrize("path", [*sorted((ROOT / "examples").glob("*.elab")),
                                  ROOT / "examples" / "vision_line" / "vision_line.elab", library_path("std")],
                         ids=lambda p: p.stem)
def test_examples_and_std_parse(path):
    module = P.parse_text(path.read_text(encoding="utf-8"), str(path))
    assert module.declarations


def test_keywords_are_contextual():
    module = P.parse_text(
        "device type A(channel: uint8) { claims adc[channel] out offset: int16 driver \"a\" }\n"
        "device step: A(channel = 1)\n"
        "var time: int16\n"
        "var period: bool\n"
        "dataflow D { on = Gain<int16>() step.offset -> on.x on.y -> time }\n"
        "chart C { initial step on { } transition on -> on when on.time > 1 s and period }\n")
    names = [d.name for d in module.declarations]
    assert names == ["A", "step", "time", "period", "D", "C"]
    dataflow = module.declarations[4]
    assert [i.name for i in dataflow.instances] == ["on"]
    assert dataflow.edges[0].src.parts == ("step", "offset")


@pytest.mark.parametrize("word", ["in", "out", "step", "offset", "channel", "time", "period", "unit", "range",
                                  "run", "exit", "entry", "state", "rate", "when", "initial", "service"])
def test_keyword_as_an_instance_name_after_an_edge(word):
    """LALR state merging gives the state after a path actions for every
    keyword that may follow an expression somewhere; such a word is still a
    name where the grammar takes no keyword."""
    module = P.parse_text(f"dataflow D {{\n    k = Const<int16>(value = 1)\n    k.y -> v\n"
                          f"    {word} = Gain<int16>()\n    k.y -> {word}.x\n}}\n"
                          f"task t period 1 ms {{ run D }}\n")
    dataflow = module.declarations[0]
    assert [i.name for i in dataflow.instances] == ["k", word]
    assert dataflow.edges[1].dst.parts == (word, "x")


def test_numbers_and_ranges():
    module = P.parse_text("param p: int16 = 0x2A range 0..1500\nvar f: float32 = 1.0e-3\nvar b: uint8 = 0b101\n"
                          "var d: uint8 = 007\n")
    p, f, b, d = module.declarations
    assert (p.default.value, p.range.low.value, p.range.high.value) == (42, 0, 1500)
    assert float(f.default.value) == 0.001
    assert (b.default.value, d.default.value) == (5, 7)


def test_inline_c_keeps_positions_and_text():
    text = 'actor type A() {\n    out y: int8\n    step {{ if (1) { y = "}"[0] == 0; }\n      y = 1; }}\n}\nvar x: bool\n'
    # the C string holds a '}': braces in C strings must balance (they do not here)
    with pytest.raises(ModelError) as info:
        P.parse_text(text)
    [d] = info.value.diagnostics
    assert (d.span.line, d.span.column, d.message) == \
        (3, 10, "inline C block '{{' is never closed by a balancing '}}'")
    text = 'actor type A() {\n    out y: int8\n    step {{ if (1) { y = 0; }\n      y = 1; }}\n}\nvar x: bool\n'
    module = P.parse_text(text)
    actor, var = module.declarations
    assert actor.code[0].code == " if (1) { y = 0; }\n      y = 1; "
    assert (var.span.line, var.span.column) == (6, 1)  # lines after the block are where they were


@pytest.mark.parametrize("label, example", [(label, example) for label, examples in E._EXAMPLES.items()
                                            for example in examples])
def test_every_example_mistake_still_fails_with_its_message(label, example):
    """The table of common mistakes is matched by parser state: a grammar
    change that moves a state must not silently disable an entry."""
    with pytest.raises(ModelError) as info:
        P.parse_text(example)
    [diagnostic] = info.value.diagnostics
    if label == E._EQUALS_IN_EXPRESSION:
        label = "compare with '==': '=' only assigns"
    assert diagnostic.message.endswith(": " + label)
