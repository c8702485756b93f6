"""Parsing ``.elab`` text into the AST.

Inline C blocks (``{{ ... }}``) run to the ``}}`` that balances the opening
``{{``, which no regular expression can find. Before lexing, the C text is
therefore blanked out (line breaks kept, so every position stays right) and
kept aside by its offset; the grammar's ``C_CODE`` terminal matches the
blanked block and the transformer puts the text back.
"""

from __future__ import annotations

import functools
import re
import threading
from fractions import Fraction
from importlib import resources

import lark
from lark import Token, Transformer, v_args
from lark.exceptions import UnexpectedCharacters, UnexpectedEOF, UnexpectedInput, UnexpectedToken, VisitError

from . import ast
from .source import Diagnostic, ModelError, Span, did_you_mean, note

_DURATION_US = {"us": 1, "ms": 1000, "s": 1_000_000}
_MAX_EXPRESSION_DEPTH = 100
_PARSE_LOCK = threading.Lock()


def _grammar_text() -> str:
    return resources.files(__package__).joinpath("elab.lark").read_text(encoding="utf-8")


@functools.lru_cache(maxsize=1)
def _ast_parser() -> tuple[lark.Lark, "_ToAst"]:
    """A parser that builds the AST while parsing, with no intermediate tree
    (about twice as fast on large models). Lark gives such callbacks no
    positions, so every token is kept and :func:`_with_span` computes the
    span from the children before dropping the punctuation and keyword
    tokens the AST does not need. The transformer is told the file and its
    inline C before each parse; parsing holds a lock."""
    transformer = _ToAst("<string>", {})
    return lark.Lark(_grammar_text(), parser="lalr", lexer="contextual", keep_all_tokens=True,
                     maybe_placeholders=False, transformer=transformer), transformer


@functools.lru_cache(maxsize=1)
def _kept_terminals() -> frozenset[str]:
    """The terminals the grammar names itself: their tokens reach the AST."""
    import re

    return frozenset(re.findall(r"^([A-Z_]+)\s*:", _grammar_text(), re.MULTILINE))


class _Meta:
    __slots__ = ("line", "column", "end_line", "end_column", "empty")

    def __init__(self, first, last) -> None:
        self.empty = first is None
        if first is not None:
            self.line, self.column = first
            self.end_line, self.end_column = last


def _bounds(item):
    """(first, last) positions inside a child: a token, an AST node or a tuple."""
    if isinstance(item, Token):
        if item.line is None:
            return None
        return (item.line, item.column), (item.end_line, item.end_column)
    span = getattr(item, "span", None)
    if isinstance(span, Span):
        return (span.line, span.column), (span.end_line, span.end_column)
    if isinstance(item, tuple):
        found = [b for b in map(_bounds, item) if b is not None]
        if found:
            return found[0][0], found[-1][1]
    return None


def _with_span(f, _data, children, _meta):
    found = [b for b in map(_bounds, children) if b is not None]
    meta = _Meta(found[0][0], found[-1][1]) if found else _Meta(None, None)
    kept = _kept_terminals()
    return f(meta, [c for c in children if not isinstance(c, Token) or c.type in kept])


# ----------------------------------------------------------- inline C blocks


def _position(text: str, offset: int) -> tuple[int, int]:
    line = text.count("\n", 0, offset) + 1
    return line, offset - (text.rfind("\n", 0, offset) + 1) + 1


def blank_inline_c(text: str, file: str) -> tuple[str, dict[int, str]]:
    """Blank the C text of every ``{{ ... }}`` block; return it by offset.

    Comments and strings of the model language are skipped, so a ``{{`` in a
    comment opens nothing. Raises :class:`ModelError` for an unclosed block.
    """
    blocks: dict[int, str] = {}
    out: list[str] = []
    i, n, copied = 0, len(text), 0
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            end = text.find("\n", i)
            i = n if end < 0 else end
        elif text.startswith("/*", i):
            end = text.find("*/", i + 2)
            i = n if end < 0 else end + 2
        elif c == '"':
            i += 1
            while i < n and text[i] not in '"\n':
                i += 2 if text[i] == "\\" else 1
            i += 1
        elif text.startswith("{{", i):
            depth, k = 0, i
            while k < n:
                if text[k] == "{":
                    depth += 1
                elif text[k] == "}":
                    depth -= 1
                    if depth == 0:
                        break
                k += 1
            if k >= n or text[k - 1] != "}":  # the braces close, but not with '}}'
                line, col = _position(text, i)
                raise ModelError([Diagnostic(Span(file, line, col, line, col + 2),
                                             "inline C block '{{' is never closed by a balancing '}}'",
                                             "braces inside inline C, in its strings and comments too, must balance")])
            body = text[i + 2:k - 1]
            blocks[i] = body
            out.append(text[copied:i + 2])
            out.append("".join(ch if ch == "\n" else " " for ch in body))
            out.append("}}")
            copied = i = k + 1
        else:
            i += 1
    out.append(text[copied:])
    return "".join(out), blocks


# ----------------------------------------------------------- tree -> AST


def _token_span(file: str, tok: Token) -> Span:
    return Span(file, tok.line, tok.column, tok.end_line, tok.end_column)


@v_args(wrapper=_with_span)
class _ToAst(Transformer):
    """Builds AST nodes bottom-up; every node gets the span of its rule."""

    def __init__(self, file: str, blocks: dict[int, str]):
        super().__init__()
        self.file = file
        self.blocks = blocks
        self.depths: dict[int, int] = {}  # id(operator node) -> its nesting depth, for one parse

    # helpers
    def _span(self, meta) -> Span:
        if getattr(meta, "empty", True):
            return Span.unknown(self.file)
        return Span(self.file, meta.line, meta.column, meta.end_line, meta.end_column)

    def _tspan(self, tok: Token) -> Span:
        return _token_span(self.file, tok)

    _ESCAPES = {"n": "\n", "t": "\t", "r": "\r", "0": "\0", '"': '"', "\\": "\\"}

    def _string(self, tok: Token) -> str:
        """The text of a string literal; its escapes are those of C's simple ones."""
        def escape(m: re.Match) -> str:
            if m.group(1) not in self._ESCAPES:
                col = tok.column + 1 + m.start()
                raise ModelError([Diagnostic(Span(self.file, tok.line, col, tok.line, col + 2),
                                             f"unknown escape '\\{m.group(1)}' in a string",
                                             "the escapes are \\n \\t \\r \\0 \\\" and \\\\")])
            return self._ESCAPES[m.group(1)]
        return re.sub(r"\\(.)", escape, tok[1:-1])

    def _number(self, tok: Token) -> int | Fraction:
        """The value of an INT or REAL token. Leading zeros are decimal; a
        literal no type can hold is an error (and never reaches int())."""
        text = str(tok)
        if len(text) > 40:
            raise ModelError([Diagnostic(self._tspan(tok), f"number '{text[:20]}...' is too long for any type")])
        if tok.type == "INT":
            base = {"0x": 16, "0b": 2}.get(text[:2].lower(), 10)
            return int(text[2:] if base != 10 else text, base)
        exponent = text.lower().partition("e")[2]
        if exponent and abs(int(exponent)) > 400:
            raise ModelError([Diagnostic(self._tspan(tok), f"real number '{text}' is out of range")])
        return Fraction(text)

    def _named(self, meta, name_tok: Token) -> dict:
        return {"span": self._span(meta), "name": str(name_tok), "name_span": self._tspan(name_tok)}

    # top level
    def start(self, meta, items):
        header = None
        imports, decls, ifaces = [], [], []
        extra_headers = []
        for item in items:
            if isinstance(item, ast.ModelDecl):
                if header is None:
                    header = item
                else:
                    extra_headers.append(item)
            elif isinstance(item, ast.Import):
                imports.append(item)
            elif isinstance(item, ast.Interface):
                ifaces.append(item)
            else:
                decls.append(item)
        if extra_headers:
            d = extra_headers[0]
            raise ModelError([Diagnostic(d.span, "a file has at most one 'model' header",
                                         notes=(note(header.span, "the first 'model' header"),))])
        return ast.Module(self.file, header, tuple(imports), tuple(decls), tuple(ifaces))

    def model_decl(self, meta, ch):
        title = self._string(ch[1]) if len(ch) > 1 else None
        return ast.ModelDecl(**self._named(meta, ch[0]), title=title)

    def import_decl(self, meta, ch):
        tok = ch[0]
        if tok.type == "STRING":
            return ast.Import(self._span(meta), self._string(tok), False)
        return ast.Import(self._span(meta), str(tok), True)

    # data
    def type_ref(self, meta, ch):
        return ast.TypeRef(self._span(meta), str(ch[0]), ch[1] if len(ch) > 1 else None)

    def const_decl(self, meta, ch):
        return ast.Const(**self._named(meta, ch[0]), type=ch[1], value=ch[2])

    def _data(self, meta, ch, kind):
        name, type_ref, rest = ch[0], ch[1], ch[2:]
        default = None
        if rest and isinstance(rest[0], ast.Expr):
            default, rest = rest[0], rest[1:]
        attrs: dict[str, object] = {}
        spans: list[tuple[str, Span]] = []
        for key, value, span in rest:
            if key in attrs:
                raise ModelError([Diagnostic(span, f"attribute '{key}' given twice",
                                             "each attribute may appear at most once")])
            attrs[key] = value
            spans.append((key, span))
        return ast.Data(**self._named(meta, name), kind=kind, type=type_ref, default=default,
                        range=attrs.get("range"), unit=attrs.get("unit"),
                        service=attrs.get("service"), persist=bool(attrs.get("persist")),
                        attr_spans=tuple(spans))

    def param_decl(self, meta, ch):
        return self._data(meta, ch, "param")

    def var_decl(self, meta, ch):
        return self._data(meta, ch, "var")

    def range_attr(self, meta, ch):
        return ("range", ast.RangeAttr(self._span(meta), ch[0], ch[2]), self._span(meta))

    def unit_attr(self, meta, ch):
        return ("unit", self._string(ch[1]), self._span(meta))

    def service_attr(self, meta, ch):
        address = ch[1] if len(ch) > 1 else None
        return ("service", ast.ServiceAttr(self._span(meta), str(ch[0]), address), self._span(meta))

    def address(self, meta, ch):
        return self._number(ch[0])

    def persist_attr(self, meta, ch):
        return ("persist", True, self._span(meta))

    def channel_decl(self, meta, ch):
        return ast.Channel(**self._named(meta, ch[0]), type=ch[1], delay=ch[2] if len(ch) > 2 else None)

    def delay(self, meta, ch):
        value = ch[0]
        if isinstance(value, tuple):
            return ast.Delay(self._span(meta), None, value)
        return ast.Delay(self._span(meta), value, None)

    def delay_list(self, meta, ch):
        return tuple(ch)

    # devices
    def formal_params(self, meta, ch):
        return tuple(c for c in ch if c is not None)

    def formal_param(self, meta, ch):
        default = choices = None
        for c in ch[2:]:
            if isinstance(c, tuple):
                choices = c
            else:
                default = c
        return ast.FormalParam(**self._named(meta, ch[0]), type=ch[1], default=default, choices=choices)

    def choices(self, meta, ch):
        return tuple(ch[1:])

    def actuals(self, meta, ch):
        return tuple(c for c in ch if c is not None)

    def actual(self, meta, ch):
        return ast.Actual(**self._named(meta, ch[0]), value=ch[1])

    def resource(self, meta, ch):
        return ast.Resource(self._span(meta), str(ch[0]), ch[1] if len(ch) > 1 else None)

    def claims(self, meta, ch):
        return ("claims", tuple(ch))

    def rate(self, meta, ch):
        return ch[0]

    def data_port(self, meta, ch):
        return ast.DataPort(**self._named(meta, ch[1]), direction=str(ch[0]), type=ch[2],
                            rate=ch[3] if len(ch) > 3 else None)

    def data_export(self, meta, ch):
        return ast.DataExport(**self._named(meta, ch[1]), direction=str(ch[0]), target=ch[2])

    def part(self, meta, ch):
        return ast.Part(**self._named(meta, ch[0]), type_name=str(ch[1]), type_span=self._tspan(ch[1]),
                        args=ch[2])

    def driver(self, meta, ch):
        return ("driver", self._string(ch[0]), self._span(meta))

    def device_type(self, meta, ch):
        name, params, members = ch[0], ch[1], ch[2:]
        claims, ports, exports, parts = [], [], [], []
        driver = driver_span = None
        for m in members:
            if isinstance(m, ast.DataPort):
                ports.append(m)
            elif isinstance(m, ast.DataExport):
                exports.append(m)
            elif isinstance(m, ast.Part):
                parts.append(m)
            elif m[0] == "claims":
                claims.extend(m[1])
            elif m[0] == "driver":
                if driver is not None:
                    raise ModelError([Diagnostic(m[2], "a device type has at most one 'driver'")])
                driver, driver_span = m[1], m[2]
        return ast.DeviceType(**self._named(meta, name), params=params, claims=tuple(claims),
                              ports=tuple(ports), exports=tuple(exports), parts=tuple(parts),
                              driver=driver, driver_span=driver_span)

    def device_decl(self, meta, ch):
        return ast.DeviceInstance(**self._named(meta, ch[0]), type_name=str(ch[1]),
                                  type_span=self._tspan(ch[1]), args=ch[2])

    # actors
    def type_params(self, meta, ch):
        return tuple(c for c in ch if isinstance(c, ast.TypeParam))

    def type_param(self, meta, ch):
        return ast.TypeParam(**self._named(meta, ch[0]), bound=str(ch[1]) if len(ch) > 1 else None)

    def actor_port(self, meta, ch):
        return ast.ActorPort(**self._named(meta, ch[1]), direction=str(ch[0]), type=ch[2],
                             rate=ch[3] if len(ch) > 3 else None)

    def state_var(self, meta, ch):
        return ast.StateVar(**self._named(meta, ch[0]), type=ch[1])

    def code_block(self, meta, ch):
        kind, code_tok = ch
        code = self.blocks.get(code_tok.start_pos, "")
        code_span = Span(self.file, code_tok.line, code_tok.column + 2, code_tok.end_line, code_tok.end_column - 2)
        return ast.CodeBlock(self._span(meta), str(kind), code, code_span)

    def impl(self, meta, ch):
        return ("impl", self._string(ch[0]), self._span(meta))

    def actor_type(self, meta, ch):
        name = ch[0]
        rest = list(ch[1:])
        type_params: tuple = ()
        if rest[0] and isinstance(rest[0][0], ast.TypeParam):
            type_params = rest.pop(0)
        params = rest.pop(0)
        ports, states, code = [], [], []
        impl = impl_span = None
        for m in rest:
            if isinstance(m, ast.ActorPort):
                ports.append(m)
            elif isinstance(m, ast.StateVar):
                states.append(m)
            elif isinstance(m, ast.CodeBlock):
                code.append(m)
            else:
                if impl is not None:
                    raise ModelError([Diagnostic(m[2], "an actor type has at most one 'impl'")])
                impl, impl_span = m[1], m[2]
        return ast.ActorType(**self._named(meta, name), type_params=type_params, params=params,
                             ports=tuple(ports), states=tuple(states), code=tuple(code),
                             impl=impl, impl_span=impl_span)

    # dataflows
    def schedule_choice(self, meta, ch):
        return str(ch[0])

    def dataflow(self, meta, ch):
        name, rest = ch[0], ch[1:]
        schedule = None
        if rest and isinstance(rest[0], str) and not isinstance(rest[0], Token):
            schedule, rest = rest[0], rest[1:]
        instances = tuple(m for m in rest if isinstance(m, ast.Instance))
        edges = tuple(m for m in rest if isinstance(m, ast.Edge))
        return ast.Dataflow(**self._named(meta, name), schedule=schedule, instances=instances, edges=edges)

    def type_args(self, meta, ch):
        return tuple(c for c in ch if isinstance(c, ast.TypeRef))

    def instance(self, meta, ch):
        name, type_name = ch[0], ch[1]
        type_args = ch[2] if len(ch) > 3 else ()
        return ast.Instance(**self._named(meta, name), type_name=str(type_name),
                            type_span=self._tspan(type_name), type_args=type_args, args=ch[-1])

    def edge(self, meta, ch):
        return ast.Edge(self._span(meta), ch[0], ch[1], ch[2] if len(ch) > 2 else None)

    # charts
    def entry_action(self, meta, ch):
        return ast.Assign(self._span(meta), "entry", ch[0], ch[1])

    def exit_action(self, meta, ch):
        return ast.Assign(self._span(meta), "exit", ch[0], ch[1])

    def run_action(self, meta, ch):
        return ast.Run(**self._named(meta, ch[0]))

    def step(self, meta, ch):
        initial = isinstance(ch[0], Token) and ch[0].type == "INITIAL"
        rest = ch[1:] if initial else ch
        name, actions = rest[1], rest[2:]  # rest[0] is the `step` keyword
        return ast.Step(**self._named(meta, name), initial=initial,
                        entry=tuple(a for a in actions if isinstance(a, ast.Assign) and a.kind == "entry"),
                        exit=tuple(a for a in actions if isinstance(a, ast.Assign) and a.kind == "exit"),
                        runs=tuple(a for a in actions if isinstance(a, ast.Run)))

    def step_set(self, meta, ch):
        return tuple(ast.StepRef(self._tspan(t), str(t), self._tspan(t)) for t in ch)

    def transition(self, meta, ch):
        return ast.Transition(self._span(meta), ch[0], ch[1], ch[2])

    def chart(self, meta, ch):
        return ast.Chart(**self._named(meta, ch[0]),
                         steps=tuple(c for c in ch[1:] if isinstance(c, ast.Step)),
                         transitions=tuple(c for c in ch[1:] if isinstance(c, ast.Transition)))

    # tasks and interfaces
    def task_attr(self, meta, ch):
        return ast.TaskAttr(self._span(meta), str(ch[0]), ch[1])

    def task(self, meta, ch):
        return ast.Task(**self._named(meta, ch[0]),
                        attrs=tuple(c for c in ch[1:] if isinstance(c, ast.TaskAttr)),
                        runs=tuple(c for c in ch[1:] if isinstance(c, ast.Run)))

    def iface_attr(self, meta, ch):
        key, value = ch
        v: int | str = self._number(value) if value.type == "INT" else str(value)
        return ast.InterfaceAttr(self._span(meta), str(key), v, self._tspan(value))

    def debug_iface(self, meta, ch):
        return ast.Interface(self._span(meta), "debug", None, ch[0], tuple(ch[1:]))

    def modbus_iface(self, meta, ch):
        mode = str(ch[0])
        resource = ch[1] if len(ch) > 1 and isinstance(ch[1], ast.Resource) else None
        attrs = tuple(c for c in ch[1:] if isinstance(c, ast.InterfaceAttr))
        return ast.Interface(self._span(meta), "modbus", mode, resource, attrs)

    # expressions
    def primary(self, meta, ch):  # "(" expr ")": the parentheses are dropped
        return ch[0]

    def int_lit(self, meta, ch):
        return ast.IntLit(self._span(meta), self._number(ch[0]))

    def real_lit(self, meta, ch):
        return ast.RealLit(self._span(meta), self._number(ch[0]), str(ch[0]))

    def duration_lit(self, meta, ch):
        number, unit = ch
        value = Fraction(self._number(number))
        return ast.DurationLit(self._span(meta), value * _DURATION_US[str(unit)], f"{number} {unit}")

    def true_lit(self, meta, ch):
        return ast.BoolLit(self._span(meta), True)

    def false_lit(self, meta, ch):
        return ast.BoolLit(self._span(meta), False)

    def string_lit(self, meta, ch):
        return ast.StringLit(self._span(meta), self._string(ch[0]))

    def path(self, meta, ch):
        return ast.Path(self._span(meta), tuple(str(t) for t in ch), tuple(self._tspan(t) for t in ch))

    def _nested(self, node: ast.Expr, *operands: ast.Expr) -> ast.Expr:
        """``node``, unless operators nest deeper than every later stage
        (which walks expressions recursively) can take."""
        depth = 1 + max(self.depths.get(id(o), 0) for o in operands)
        if depth > _MAX_EXPRESSION_DEPTH:
            raise ModelError([Diagnostic(node.span, f"expression nested more than {_MAX_EXPRESSION_DEPTH} "
                                                    "operators deep", "split it up with consts")])
        self.depths[id(node)] = depth
        return node

    def binary(self, meta, ch):
        left, op, right = ch
        return self._nested(ast.Binary(self._span(meta), str(op), left, right), left, right)

    def unary(self, meta, ch):
        op, operand = ch
        return self._nested(ast.Unary(self._span(meta), str(op), operand), operand)


# ----------------------------------------------------------- syntax errors

_TERMINAL_WORDS = {
    "NAME": "a name", "INT": "an integer", "REAL": "a real number", "STRING": "a string",
    "C_CODE": "an inline C block '{{ ... }}'", "$END": "the end of the file",
}

# Common mistakes, recognised by the parser state they fail in and the kind
# of token found there.
_EQUALS_IN_EXPRESSION = "'=' in an expression"
_INITIAL_VALUE_LATE = "the initial value '= ...' comes right after the type, before the attributes"
_RANGE_FORM = "a range is written low..high, as in 'range 0..100'"
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
        "param p: int16 unit \"u\" = 3", "param p: int16 persist = 3", "param p: int16 service rw = 3"],
    _RANGE_FORM: [
        "param p: int16 range 1 }", "param p: int16 range x y"],
}

# Where a top-level declaration may start: the keywords that begin one.
_DECLARATION_KEYWORDS = ("model", "import", "const", "param", "var", "channel", "device", "actor",
                         "dataflow", "chart", "task", "debug", "modbus")
_OPERATORS = {"EQ", "NE", "LE", "GE", "LT", "GT", "OR", "AND", "PLUS", "MINUS", "STAR", "SLASH", "PERCENT"}
_OPERAND_STARTS = {"INT", "REAL", "STRING", "NAME", "LPAR", "MINUS", "NOT", "TRUE", "FALSE"}


@functools.lru_cache(maxsize=1)
def _example_errors() -> tuple:
    """(label, parser state, token type) of every example mistake."""
    found = []
    for label, examples in _EXAMPLES.items():
        for example in examples:
            try:
                _ast_parser()[0].parse(example)
            except (UnexpectedToken, UnexpectedEOF) as err:
                found.append((label, err.state.position, err.token.type))
            except (UnexpectedInput, ModelError):
                pass
    return tuple(found)


def _match_example(err: UnexpectedInput) -> str | None:
    """The label of the example mistake that fails in the same parser state
    on the same kind of token. (Lark's ``match_examples`` also compares the
    depth of the parser stack, which depends on how many declarations or
    statements come before the mistake, so it misses most real ones.)"""
    if not isinstance(err, (UnexpectedToken, UnexpectedEOF)) or err.state is None:
        return None
    for label, position, token_type in _example_errors():
        if position == err.state.position and token_type == err.token.type:
            return label
    return None


def _describe_terminal(name: str) -> str:
    if name in _TERMINAL_WORDS:
        return _TERMINAL_WORDS[name]
    try:
        pattern = _ast_parser()[0].get_terminal(name).pattern
    except KeyError:
        return name
    return f"'{pattern.value}'" if pattern.type == "str" else name.lower()


def _describe_expected(accepts) -> str:
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
    names = sorted({_describe_terminal(t) for t in accepts}, key=lambda w: (not w[0].isalpha(), w))
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
    line, col = _position(text, len(text.rstrip()))
    return Span(file, line, col, line, col + 1)


def _equals_message(text: str, tok: Token) -> str:
    """What a '=' inside an expression means: a comparison, or a param or
    var whose initial value or range is misplaced."""
    line = text[text.rfind("\n", 0, tok.start_pos) + 1:tok.start_pos]
    if re.match(r"\s*(param|var)\b", line):
        after_range = re.split(r"\brange\b", line)
        return _RANGE_FORM if len(after_range) > 1 and ".." not in after_range[-1] else _INITIAL_VALUE_LATE
    return "compare with '==': '=' only assigns"


def _syntax_error(err: UnexpectedInput, file: str, text: str) -> Diagnostic:
    message = _match_example(err)
    if message == _EQUALS_IN_EXPRESSION:
        message = _equals_message(text, err.token)
    hint = None
    position = err.token.start_pos if isinstance(err, UnexpectedToken) else err.pos_in_stream
    if position is not None and text.startswith("/*", position):
        line, col = _position(text, position)
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
        span = _end_span(file, text) if tok.type == "$END" else _token_span(file, tok)
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
            base += f", expected {_describe_expected(accepts)}"
    else:  # UnexpectedEOF
        span = _end_span(file, text)
        base = "unexpected end of the file"
    if message:
        return Diagnostic(span, f"{base}: {message}", hint)
    return Diagnostic(span, base, hint)


_WORD = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def _keyword_as_name(err: UnexpectedInput) -> bool:
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


def parse_text(text: str, file: str = "<string>") -> ast.Module:
    """Parse model text into an :class:`ast.Module`; raise :class:`ModelError`."""
    blanked, blocks = blank_inline_c(text, file)
    parser, transformer = _ast_parser()
    with _PARSE_LOCK:
        transformer.file, transformer.blocks, transformer.depths = file, blocks, {}
        try:
            return parser.parse(blanked, on_error=_keyword_as_name)
        except UnexpectedInput as err:
            raise ModelError([_syntax_error(err, file, blanked)]) from None
        except VisitError as err:
            if isinstance(err.orig_exc, ModelError):
                raise err.orig_exc from None
            raise
