"""Building the AST while parsing: Lark's LALR parser calls the
transformer's callbacks as it reduces, with no intermediate tree (about
twice as fast on large models). Lark gives such callbacks no positions, so
every token is kept and :func:`_with_span` computes the span from the
children before dropping the punctuation and keyword tokens the AST does
not need."""

from __future__ import annotations

import re
from fractions import Fraction

from lark import Token, Transformer, v_args

from ..core.source import Diagnostic, ModelError, Span, note
from . import ast
from .grammar import kept_terminals

_DURATION_US = {"us": 1, "ms": 1000, "s": 1_000_000}
_MAX_EXPRESSION_DEPTH = 100


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
    kept = kept_terminals()
    return f(meta, [c for c in children if not isinstance(c, Token) or c.type in kept])


# The longest name (docs/language.md, "Lexical structure"): C99 keeps 63
# significant characters of an identifier, and a dotted path of a few such
# names stays far below C89's 509 characters of a string literal.
MAX_NAME_LENGTH = 63
# The longest string, in bytes of its UTF-8: a title is a C string literal
# of as many characters, within C89's 509 however it is escaped.
MAX_STRING_BYTES = 255


def token_span(file: str, tok: Token) -> Span:
    return Span(file, tok.line, tok.column, tok.end_line, tok.end_column)


@v_args(wrapper=_with_span)
class ToAst(Transformer):
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
        return token_span(self.file, tok)

    def checked_name(self, tok: Token) -> Token:
        """A NAME token, refused beyond MAX_NAME_LENGTH characters: names
        reach C identifiers and the strings of the debug and service tables,
        which compilers limit (C89's 509-character string literals)."""
        if len(tok) > MAX_NAME_LENGTH:
            raise ModelError([Diagnostic(self._tspan(tok), f"name '{tok[:20]}...' has {len(tok)} characters, "
                                                           f"more than the {MAX_NAME_LENGTH} a name may have")])
        return tok

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
        text = re.sub(r"\\(.)", escape, tok[1:-1])
        if len(text.encode("utf-8", "surrogatepass")) > MAX_STRING_BYTES:
            raise ModelError([Diagnostic(self._tspan(tok), f"string of {len(text.encode('utf-8', 'surrogatepass'))} "
                                                           f"bytes in UTF-8, more than the {MAX_STRING_BYTES} a "
                                                           "string may have")])
        return text

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
        imports, decls, ifaces, exports, remote = [], [], [], [], []
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
            elif isinstance(item, ast.Export):
                exports.append(item)
            elif isinstance(item, ast.RemoteSettings):
                remote.append(item)
            else:
                decls.append(item)
        if extra_headers:
            d = extra_headers[0]
            raise ModelError([Diagnostic(d.span, "a file has at most one 'model' header",
                                         notes=(note(header.span, "the first 'model' header"),))])
        return ast.Module(self.file, header, tuple(imports), tuple(decls), tuple(ifaces),
                          exports=tuple(exports), remote=tuple(remote))

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
                        attr_spans=tuple(spans), scale=attrs.get("scale"))

    def param_decl(self, meta, ch):
        return self._data(meta, ch, "param")

    def var_decl(self, meta, ch):
        return self._data(meta, ch, "var")

    def range_attr(self, meta, ch):
        return ("range", ast.RangeAttr(self._span(meta), ch[0], ch[2]), self._span(meta))

    def unit_attr(self, meta, ch):
        return ("unit", self._string(ch[1]), self._span(meta))

    def scale_attr(self, meta, ch):
        return ("scale", Fraction(self._number(ch[1])), self._span(meta))

    def service_attr(self, meta, ch):
        address = ch[1] if len(ch) > 1 else None
        return ("service", ast.ServiceAttr(self._span(meta), str(ch[0]), address), self._span(meta))

    def address(self, meta, ch):
        return self._number(ch[0])

    def persist_attr(self, meta, ch):
        return ("persist", True, self._span(meta))

    def channel_decl(self, meta, ch):
        delay = next((c for c in ch[2:] if isinstance(c, ast.Delay)), None)
        over = next((c for c in ch[2:] if isinstance(c, ast.Placement)), None)
        return ast.Channel(**self._named(meta, ch[0]), type=ch[1], delay=delay, over=over)

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

    def claim(self, meta, ch):
        if len(ch) == 1:
            return ch[0]
        r = ch[0]
        return ast.Resource(self._span(meta), r.kind, r.index, str(ch[1]), ch[2])

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
        return ("driver", self._string(ch[0]), self._span(meta), tuple(ch[1:]))

    def driver_impl(self, meta, ch):
        return ast.DriverImpl(self._span(meta), str(ch[0]), self._tspan(ch[0]), self._string(ch[1]))

    def driver_sim(self, meta, ch):
        return ast.ChipModel(self._span(meta), self._string(ch[0]))

    def device_type(self, meta, ch):
        name, params, members = ch[0], ch[1], ch[2:]
        claims, ports, exports, parts, states = [], [], [], [], []
        driver = driver_span = None
        impls: tuple = ()
        chips: tuple = ()
        for m in members:
            if isinstance(m, ast.DataPort):
                ports.append(m)
            elif isinstance(m, ast.DataExport):
                exports.append(m)
            elif isinstance(m, ast.Part):
                parts.append(m)
            elif isinstance(m, ast.StateVar):
                states.append(m)
            elif m[0] == "claims":
                claims.extend(m[1])
            elif m[0] == "driver":
                if driver is not None:
                    raise ModelError([Diagnostic(m[2], "a device type has at most one 'driver'")])
                driver, driver_span = m[1], m[2]
                impls = tuple(x for x in m[3] if isinstance(x, ast.DriverImpl))
                chips = tuple(x for x in m[3] if isinstance(x, ast.ChipModel))
        return ast.DeviceType(**self._named(meta, name), params=params, claims=tuple(claims),
                              ports=tuple(ports), exports=tuple(exports), parts=tuple(parts),
                              driver=driver, driver_span=driver_span, impls=impls, states=tuple(states),
                              chips=chips)

    def device_decl(self, meta, ch):
        return ast.DeviceInstance(**self._named(meta, ch[0]), type_name=str(ch[1]),
                                  type_span=self._tspan(ch[1]), args=ch[2],
                                  node=next((c for c in ch[3:] if isinstance(c, ast.Placement)), None),
                                  safe=next((c for c in ch[3:] if isinstance(c, tuple)), ()))

    def safe_values(self, meta, ch):
        return tuple(ch)

    def safe_value(self, meta, ch):
        return ast.SafeValue(self._span(meta), ch[0], ch[1])

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

    def actor_cost(self, meta, ch):
        return ("cost", ch[0], self._span(meta))

    def actor_type(self, meta, ch):
        name = ch[0]
        rest = list(ch[1:])
        type_params: tuple = ()
        if rest[0] and isinstance(rest[0][0], ast.TypeParam):
            type_params = rest.pop(0)
        params = rest.pop(0)
        ports, states, code = [], [], []
        impl = impl_span = cost = None
        for m in rest:
            if isinstance(m, ast.ActorPort):
                ports.append(m)
            elif isinstance(m, ast.StateVar):
                states.append(m)
            elif isinstance(m, ast.CodeBlock):
                code.append(m)
            elif m[0] == "cost":
                if cost is not None:
                    raise ModelError([Diagnostic(m[2], "an actor type has at most one 'cost'")])
                cost = m
            else:
                if impl is not None:
                    raise ModelError([Diagnostic(m[2], "an actor type has at most one 'impl'")])
                impl, impl_span = m[1], m[2]
        return ast.ActorType(**self._named(meta, name), type_params=type_params, params=params,
                             ports=tuple(ports), states=tuple(states), code=tuple(code),
                             impl=impl, impl_span=impl_span, cost=cost[1] if cost else None,
                             cost_span=cost[2] if cost else None)

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
                        runs=tuple(c for c in ch[1:] if isinstance(c, ast.Run)),
                        node=next((c for c in ch[1:] if isinstance(c, ast.Placement)), None))

    def remote_attr(self, meta, ch):
        return ast.RemoteAttr(self._span(meta), str(ch[0]), ch[1])

    def remote_settings(self, meta, ch):
        return ast.RemoteSettings(self._span(meta), tuple(ch))

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

    # distribution
    def _placement(self, meta, ch):
        return ast.Placement(**self._named(meta, ch[0]))

    placement = channel_over = _placement

    def node_mcu(self, meta, ch):
        return ("mcu", ch[0])

    def node_cores(self, meta, ch):
        return ("cores", int(ch[0]), self._tspan(ch[0]))

    def node_decl(self, meta, ch):
        mcu = next((str(c[1]) for c in ch[2:] if isinstance(c, tuple) and c[0] == "mcu"), None)
        cores = next((c for c in ch[2:] if isinstance(c, tuple) and c[0] == "cores"), None)
        title = next((self._string(c) for c in ch[2:] if isinstance(c, Token) and c.type == "STRING"), None)
        return ast.NodeDecl(**self._named(meta, ch[0]), board=str(ch[1]), board_span=self._tspan(ch[1]),
                            mcu=mcu, title=title, cores=cores[1] if cores else None,
                            cores_span=cores[2] if cores else None)

    def link_engine(self, meta, ch):
        return "dds" if ch[0].type == "DDS" else "modbus-" + str(ch[0])

    def link_attr(self, meta, ch):
        return ast.LinkAttr(self._span(meta), str(ch[0]), ch[1])

    def link_member(self, meta, ch):
        resource = next((c for c in ch[2:] if isinstance(c, ast.Resource)), None)
        return ast.LinkMember(self._span(meta), str(ch[0]), str(ch[1]), self._tspan(ch[1]), resource,
                              tuple(c for c in ch[2:] if isinstance(c, ast.LinkAttr)))

    def link_decl(self, meta, ch):
        return ast.LinkDecl(**self._named(meta, ch[0]), engine=ch[1],
                            attrs=tuple(c for c in ch[2:] if isinstance(c, ast.LinkAttr)),
                            members=tuple(c for c in ch[2:] if isinstance(c, ast.LinkMember)))

    def export_decl(self, meta, ch):
        link = ast.Placement(self._tspan(ch[1]), str(ch[1]), self._tspan(ch[1]))
        return ast.Export(self._span(meta), str(ch[0]), self._tspan(ch[0]), link)

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
