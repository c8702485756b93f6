"""Syntax errors in the model's words: what was found, what was expected,
and for the usual mistakes what they mean (the examples table)."""

from __future__ import annotations

import functools
import re

from lark import Token
from lark.exceptions import UnexpectedCharacters, UnexpectedEOF, UnexpectedInput, UnexpectedToken

from ..core.source import Diagnostic, ModelError, Span, did_you_mean
from .inline_c import position
from .to_ast import token_span


_TERMINAL_WORDS = {
    "NAME": "a name", "INT": "an integer", "REAL": "a real number", "STRING": "a string",
    "C_CODE": "an inline C block '{{ ... }}'", "$END": "the end of the file",
}

# Common mistakes, recognised by the parser state they fail in and the kind
# of token found there.
_EQUALS_IN_EXPRESSION = "'=' in an expression"
_INITIAL_VALUE_LATE = "the initial value '= ...' comes right after the type, before the attributes"
_RANGE_FORM = "a range is written low..high, as in 'range 0..100'"
_SCALE_FORM = "a scale is a positive decimal number, as in 'scale 0.1'"
_EXAMPLES = {
    "an edge needs '->' between its source and its destination": [
        "dataflow D { a.y b.x }", "dataflow D { a b }", "dataflow D { a.y = b.x }"],
    "a declaration needs ':' and a type, as in 'var speed: int16'": [
        "var x = 1", "param p = 1", "var x", "const C = 1", "var x int16", "var x: = 1", "const C: = 1",
        "param p: = 1"],
    "a transition needs 'when' and a guard, as in 'transition A -> B when go'": [
        "chart C { step A {} transition A -> B }", "chart C { step A {} transition A -> B step X {} }"],
    _EQUALS_IN_EXPRESSION: [  # told apart by _equals_message
        "chart C { transition A -> B when x = 1 }", "chart C { transition A -> B when 1 = 1 }",
        "chart C { transition A -> B when x.y = 1 }"],
    _INITIAL_VALUE_LATE: [
        "param p: int16 unit \"u\" = 3", "param p: int16 persist = 3", "param p: int16 service rw = 3",
        "param p: int16 scale 0.1 = 3"],
    _RANGE_FORM: [
        "param p: int16 range 1 }", "param p: int16 range x y"],
    _SCALE_FORM: [
        "param p: int16 scale -1", "param p: int16 scale \"0.1\"", "param p: int16 scale x", "param p: int16 scale"],
}

# Where a top-level declaration may start: the keywords that begin one.
_DECLARATION_KEYWORDS = ("model", "import", "const", "param", "var", "channel", "device", "actor",
                         "dataflow", "chart", "task", "debug", "modbus")
_OPERATORS = {"EQ", "NE", "LE", "GE", "LT", "GT", "OR", "AND", "PLUS", "MINUS", "STAR", "SLASH", "PERCENT"}
_OPERAND_STARTS = {"INT", "REAL", "STRING", "NAME", "LPAR", "MINUS", "NOT", "TRUE", "FALSE"}


@functools.lru_cache(maxsize=1)
def _example_errors(parser) -> tuple:
    """(label, parser state, token type) of every example mistake."""
    found = []
    for label, examples in _EXAMPLES.items():
        for example in examples:
            try:
                parser.parse(example)
            except (UnexpectedToken, UnexpectedEOF) as err:
                found.append((label, err.state.position, err.token.type))
            except (UnexpectedInput, ModelError):
                pass
    return tuple(found)


def _match_example(err: UnexpectedInput, parser) -> str | None:
    """The label of the example mistake that fails in the same parser state
    on the same kind of token. (Lark's ``match_examples`` also compares the
    depth of the parser stack, which depends on how many declarations or
    statements come before the mistake, so it misses most real ones.)"""
    if not isinstance(err, (UnexpectedToken, UnexpectedEOF)) or err.state is None:
        return None
    for label, state, token_type in _example_errors(parser):
        if state == err.state.position and token_type == err.token.type:
            return label
    return None


def _describe_terminal(name: str, parser) -> str:
    if name in _TERMINAL_WORDS:
        return _TERMINAL_WORDS[name]
    try:
        pattern = parser.get_terminal(name).pattern
    except KeyError:
        return name
    return f"'{pattern.value}'" if pattern.type == "str" else name.lower()


def _describe_expected(accepts, parser) -> str:
    """The terminals a parser state accepts, in words, operators summarised."""
    accepts = set(accepts)
    words = []
    if len(accepts & _OPERAND_STARTS) >= 5:
        words.append("an expression")
        accepts -= _OPERAND_STARTS
    if len(accepts & _OPERATORS) >= 5:
        words.append("an operator")
        accepts -= _OPERATORS
    declaration = "DATAFLOW" in accepts
    if declaration:
        accepts -= {k.upper() for k in _DECLARATION_KEYWORDS} | {"$END"}
    names = sorted({_describe_terminal(t, parser) for t in accepts}, key=lambda w: (not w[0].isalpha(), w))
    words.extend(names)
    if declaration:
        words.append("a declaration")
    return ", ".join(words[:8]) + (", ..." if len(words) > 8 else "")


def _describe_token(tok: Token) -> str:
    if tok.type == "$END":
        return "end of the file"
    if tok.type == "C_CODE":
        return "an inline C block"
    return f"'{tok}'"


def _end_span(file: str, text: str) -> Span:
    """Just after the last thing in the file (lines count '\n' only, as the lexer does)."""
    line, col = position(text, len(text.rstrip()))
    return Span(file, line, col, line, col + 1)


def _equals_message(text: str, tok: Token) -> str:
    """What a '=' inside an expression means: a comparison, or a param or
    var whose initial value or range is misplaced."""
    line = text[text.rfind("\n", 0, tok.start_pos) + 1:tok.start_pos]
    if re.match(r"\s*(param|var)\b", line):
        after_range = re.split(r"\brange\b", line)
        return _RANGE_FORM if len(after_range) > 1 and ".." not in after_range[-1] else _INITIAL_VALUE_LATE
    return "compare with '==': '=' only assigns"


def syntax_error(err: UnexpectedInput, file: str, text: str, parser) -> Diagnostic:
    """The diagnostic of a parse error; ``parser`` (the Lark parser) also
    parses the examples table once to learn where each mistake fails."""
    message = _match_example(err, parser)
    if message == _EQUALS_IN_EXPRESSION:
        message = _equals_message(text, err.token)
    hint = None
    at = err.token.start_pos if isinstance(err, UnexpectedToken) else err.pos_in_stream
    if at is not None and text.startswith("/*", at):
        line, col = position(text, at)
        return Diagnostic(Span(file, line, col, line, col + 2), "comment '/*' is never closed by '*/'")
    if isinstance(err, UnexpectedCharacters):
        line, col = err.line, err.column
        span = Span(file, line, col, line, col + 1)
        if text.startswith('"', err.pos_in_stream):
            return Diagnostic(span, "string is never closed: a string ends with '\"' on the same line")
        found = f"character '{text[err.pos_in_stream]}'" if err.pos_in_stream < len(text) else "end of file"
        base = f"unexpected {found}"
    elif isinstance(err, UnexpectedToken):
        tok = err.token
        span = _end_span(file, text) if tok.type == "$END" else token_span(file, tok)
        accepts = err.accepts or err.expected
        base = f"unexpected {_describe_token(tok)}"
        if not message and tok.type == "NAME" and "DATAFLOW" in accepts:
            # a name where a declaration starts: a misspelt keyword, or a
            # dataflow statement outside a dataflow
            if re.match(r"[ \t]*(\.|->|=[ \t]*[A-Za-z_]\w*[ \t]*[<(])", text[tok.end_pos:]):
                message = "edges and actor instances belong inside a 'dataflow { ... }'"
            else:
                return Diagnostic(span, f"{base}, expected a declaration ({', '.join(_DECLARATION_KEYWORDS)})",
                                  did_you_mean(str(tok), _DECLARATION_KEYWORDS))
        if accepts and not message:
            base += f", expected {_describe_expected(accepts, parser)}"
    else:  # UnexpectedEOF
        span = _end_span(file, text)
        base = "unexpected end of the file"
    if message:
        return Diagnostic(span, f"{base}: {message}", hint)
    return Diagnostic(span, base, hint)


_WORD = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def keyword_as_name(err: UnexpectedInput) -> bool:
    """Make a keyword the parser cannot take here a name, if it can take one.

    The contextual lexer lexes a word as a keyword wherever the LALR state
    has an action for it, and merged LALR states have actions for keywords
    that may follow an expression anywhere (``offset`` after a task's
    period, ``step`` after a guard, ``in`` after a default). A word is a
    keyword only where the grammar expects one (docs/language.md, §1).
    """
    tok = getattr(err, "token", None)
    if (isinstance(err, UnexpectedToken) and tok.type != "NAME" and _WORD.fullmatch(tok)
            and "NAME" in err.accepts):
        err.interactive_parser.feed_token(tok.update(type="NAME"))
        return True
    return False
