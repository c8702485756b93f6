"""The canonical layout of ``.elab`` text (``easylab fmt``, docs/language.md,
"Formatting").

The text is parsed twice: by the front end's parser, so a model that does
not parse is refused with its usual diagnostic, and into a concrete tree of
every token, with the comments the grammar ignores collected on the side.
The layout is then rebuilt from the tokens: line breaks stay where the
author put them, indentation, spacing and blank lines are the formatter's,
runs of like lines are aligned in columns. Comments and inline C are copied
as written. The result is parsed again and must give the same AST as the
original (spans aside): a layout that changed a model's meaning would be a
bug, reported as one instead of written.
"""

from __future__ import annotations

import dataclasses
import functools
import threading
from dataclasses import dataclass

import lark
from lark import Token, Tree

from . import ast
from .grammar import grammar_text
from .inline_c import blank_inline_c
from .loader import as_if_read
from .parser import _cached_lark, parse_text
from .syntax_errors import keyword_as_name

INDENT = "    "
COMMENT_GAP = 3  # spaces at least between code and a comment after it
COMMENT_TYPES = ("COMMENT", "BLOCK_COMMENT")

# Rules whose nodes are statements: one declaration or member each, the
# units that lines align by and that share a line only two spaces apart.
STATEMENTS = frozenset({
    "model_decl", "import_decl", "const_decl", "param_decl", "var_decl", "channel_decl", "device_type",
    "device_decl", "actor_type", "dataflow", "chart", "task", "debug_iface", "modbus_iface", "node_decl",
    "link_decl", "export_decl", "remote_settings",
    "claims", "data_port", "data_export", "part", "driver", "state_var", "actor_port", "code_block", "impl",
    "actor_cost",
    "instance", "edge", "step", "transition", "entry_action", "exit_action", "run_action", "link_member",
})

# Statements aligned in columns when they stand on consecutive lines: the
# class they align with, and where their columns start (a token index, or
# the text of the token that starts a column).
_DATA_COLUMNS = (1, 3, "=", "range", "unit", "scale", "service", "persist")
_ALIGN = {
    "param_decl": ("data", _DATA_COLUMNS), "var_decl": ("data", _DATA_COLUMNS),
    "const_decl": ("const", (3,)), "channel_decl": ("channel", (3,)),
    "actor_port": ("port", (1,)), "data_port": ("port", (1,)), "data_export": ("port", (1,)),
    "device_decl": ("device", (3,)), "part": ("part", (3,)),
    "instance": ("instance", (1,)), "edge": ("edge", ("->",)), "transition": ("transition", ("->", "when")),
    "task": ("task", ("on", "period", "{")), "step": ("step", ("{",)),
    "node_decl": ("node", (2,)), "link_member": ("member", (1,)),
}


_TYPE_LISTS = ("type_params", "type_args")


class FormatError(Exception):
    """The formatter's own failure: its layout would change the model."""


@dataclass
class Tok:
    """A token of the text as it is laid out: its text as written, where it
    stands, and what the grammar made of it."""

    type: str
    text: str
    line: int
    end_line: int
    rule: str = ""  # the rule whose node holds the token
    stmt: Tree | None = None  # the innermost statement holding it
    stmt_start: bool = False  # first token of that statement
    stmt_end: bool = False  # last token of that statement

    @property
    def is_comment(self) -> bool:
        return self.type in COMMENT_TYPES


_TREE_LOCK = threading.Lock()
_comments: list[Token] = []


def _collect_comment(tok: Token) -> Token:
    _comments.append(tok)
    return tok


@functools.lru_cache(maxsize=1)
def _tree_parser() -> lark.Lark:
    """The grammar's parser building a tree of every token, its comments
    handed to :func:`_collect_comment` (it is cached on disk like the
    front end's; it has no transformer, so its cache file is its own)."""
    options = dict(parser="lalr", lexer="contextual", keep_all_tokens=True, maybe_placeholders=False,
                   lexer_callbacks={t: _collect_comment for t in COMMENT_TYPES})
    return _cached_lark(grammar_text(), options)


def _tokens(text: str, file: str) -> list[Tok]:
    """Every token of ``text``, comments and inline C blocks with their
    text as written, in order."""
    blanked, _ = blank_inline_c(text, file)
    with _TREE_LOCK:
        _comments.clear()
        tree = _tree_parser().parse(blanked, on_error=keyword_as_name)
        comments = list(_comments)
    found: list[tuple[int, Tok]] = []

    def walk(node: Tree, stmt: Tree | None) -> None:
        if node.data in STATEMENTS:
            stmt = node
        for child in node.children:
            if isinstance(child, Tree):
                walk(child, stmt)
            else:
                written = text[child.start_pos:child.end_pos]
                found.append((child.start_pos, Tok(child.type, written, child.line, child.end_line,
                                                   str(node.data), stmt)))
    walk(tree, None)
    first: dict[int, Tok] = {}
    last: dict[int, Tok] = {}
    for _, tok in found:
        if tok.stmt is not None:
            first.setdefault(id(tok.stmt), tok).stmt_start = True
            last[id(tok.stmt)] = tok
    for tok in last.values():
        tok.stmt_end = True
    for c in comments:
        found.append((c.start_pos, Tok(c.type, str(c).rstrip() if c.type == "COMMENT" else str(c),
                                       c.line, c.end_line)))
    found.sort(key=lambda item: item[0])
    return [t for _, t in found]


def _space(prev: Tok, cur: Tok) -> str:
    """The space between two tokens on one line."""
    if cur.is_comment or prev.is_comment:
        return " "
    if cur.stmt_start and cur.stmt is not prev.stmt and prev.text != "{":
        return "  "  # two statements on one line
    if prev.text in ("(", "[", ".", "..") or (prev.text == "<" and prev.rule in _TYPE_LISTS):
        return ""
    if cur.text in (")", "]", ",", ":", ".", ".."):
        return ""
    if cur.text == "(" and cur.rule in ("actuals", "formal_params"):
        return ""
    if cur.text == "[" and cur.rule in ("type_ref", "resource"):
        return ""
    if cur.text in ("<", ">") and cur.rule in _TYPE_LISTS:
        return ""
    if prev.type == "MINUS" and prev.rule == "unary":
        return ""
    return " "


def _closers_first(toks: list[Tok]) -> int:
    """How many closing brackets start the line."""
    n = 0
    for t in toks:
        if t.text in ("}", ")", "]"):
            n += 1
        else:
            break
    return n


@dataclass
class _Line:
    toks: list[Tok]
    depth: int
    blank_before: bool
    cells: list[tuple[object, str]] = dataclasses.field(default_factory=list)  # (column key, text)
    comment: str = ""  # a trailing comment, laid out after the cells
    align: str = ""  # the class of statements it aligns with, "" for none

    @property
    def code_width(self) -> int:
        return len(self.code)

    @property
    def code(self) -> str:
        return " ".join(text for _, text in self.cells)


def _lines(toks: list[Tok]) -> list[_Line]:
    """The tokens split at the author's line breaks, each line with its depth
    of brackets and whether a blank line went before it."""
    lines: list[_Line] = []
    depth = 0
    prev: Tok | None = None
    for tok in toks:
        if prev is None or tok.line > prev.end_line:
            blank = prev is not None and tok.line > prev.end_line + 1
            lines.append(_Line([], depth, blank))
        lines[-1].toks.append(tok)
        if not tok.is_comment and tok.type != "STRING":
            if tok.text in ("{", "(", "["):
                depth += 1
            elif tok.text in ("}", ")", "]"):
                depth -= 1
        prev = tok
    for i, line in enumerate(lines):
        line.depth = max(0, line.depth - _closers_first(line.toks))
        after_opener = i > 0 and lines[i - 1].toks[-1].text == "{"
        if i == 0 or after_opener or line.toks[0].text == "}":
            line.blank_before = False
    return lines


def _cells(line: _Line) -> None:
    """Split a line into its columns (keyed by the anchor that starts each)
    and its trailing comment."""
    toks = line.toks
    if len(toks) > 1 and toks[-1].is_comment and not toks[-2].is_comment and not any("\n" in t.text for t in toks):
        line.comment, toks = toks[-1].text, toks[:-1]
    starts: dict[int, object] = {}
    stmt = toks[0].stmt
    single = (toks[0].stmt_start and toks[-1].stmt_end and stmt is not None
              and all(t.stmt is stmt or _within(t, stmt) for t in toks)
              and not any("\n" in t.text for t in toks))
    if single and stmt.data in _ALIGN:
        line.align, anchors = _ALIGN[stmt.data]
        last = 0
        for anchor in anchors:
            if isinstance(anchor, int):
                hit = anchor if anchor < len(toks) else None
            else:
                hit = next((i for i, t in enumerate(toks)
                            if t.text == anchor and t.stmt is stmt and t.type != "NAME"), None)
            if hit is not None and hit > last:
                starts[hit] = anchor
                last = hit
    cells, key, current = [], None, ""
    for i, tok in enumerate(toks):
        if i in starts:
            cells.append((key, current))
            key, current = starts[i], tok.text
        else:
            current += (_space(toks[i - 1], tok) if i else "") + tok.text
    cells.append((key, current))
    line.cells = cells


def _within(tok: Tok, stmt: Tree) -> bool:
    """Whether ``tok`` belongs to a statement nested in ``stmt``."""
    return tok.stmt is not None and any(tok.stmt is s for s in stmt.iter_subtrees())


def _align(lines: list[_Line]) -> None:
    """Pad the columns of runs of like lines (consecutive, same depth, same
    class) and the trailing comments of consecutive lines to one column."""
    def runs(key):
        run: list[_Line] = []
        for line in lines:
            if run and (line.blank_before or key(line) != key(run[-1]) or line.depth != run[-1].depth):
                yield run
                run = []
            if key(line):
                run.append(line)
            elif run:
                yield run
                run = []
        if run:
            yield run

    for run in runs(lambda ln: ln.align):
        _align_columns(run)
    for run in runs(lambda ln: bool(ln.comment)):
        column = max(len(INDENT) * ln.depth + ln.code_width for ln in run) + COMMENT_GAP
        for ln in run:
            ln.comment = " " * (column - len(INDENT) * ln.depth - ln.code_width) + ln.comment


def _align_columns(run: list[_Line]) -> None:
    """Lay out each line's cells in the run's columns: a column is as wide
    as its widest cell followed by another, a line without a column's cell
    has blanks there if it has a later one."""
    keys = [None] + list(_ALIGN[run[0].toks[0].stmt.data][1])
    order = {k: i for i, k in enumerate(keys)}
    width = {}
    for ln in run:
        for (key, text), _ in zip(ln.cells, ln.cells[1:]):
            width[key] = max(width.get(key, 0), len(text))
    for ln in run:
        laid, present = [], dict(ln.cells)
        last = order[ln.cells[-1][0]]
        for key in keys[:last + 1]:
            if key == ln.cells[-1][0]:
                laid.append((key, present[key]))
            elif key in present:
                laid.append((key, present[key].ljust(width[key])))
            elif key in width:
                laid.append((key, " " * width[key]))
        ln.cells = laid


def _render(lines: list[_Line]) -> str:
    out: list[str] = []
    for line in lines:
        if line.blank_before:
            out.append("")
        out.append((INDENT * line.depth + line.code + line.comment).rstrip(" \t"))
    return "\n".join(out) + "\n" if out else ""


def layout(text: str, file: str = "<string>") -> str:
    """The canonical layout of model text that parses (see module doc)."""
    lines = _lines(_tokens(text, file))
    for line in lines:
        _cells(line)
    _align(lines)
    return _render(lines)


def _without_spans(value):
    """An AST with its spans dropped, for comparing meanings."""
    if isinstance(value, ast.Span):
        return None
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return (type(value).__name__,) + tuple((f.name, _without_spans(getattr(value, f.name)))
                                              for f in dataclasses.fields(value) if f.name != "span")
    if isinstance(value, (list, tuple)):
        return tuple(_without_spans(v) for v in value)
    if isinstance(value, dict):
        return tuple(sorted((k, _without_spans(v)) for k, v in value.items()))
    return value


def same_meaning(text_a: str, text_b: str) -> bool:
    """Whether two model texts parse to the same AST, spans aside."""
    return _without_spans(parse_text(text_a)) == _without_spans(parse_text(text_b))


def format_text(text: str, file: str = "<string>") -> str:
    """The model ``text`` laid out canonically. Raises :class:`ModelError`
    (the parser's file:line:col diagnostic) for a text that does not parse,
    :class:`FormatError` if the layout would change its meaning."""
    text = as_if_read(text)
    original = parse_text(text, file)
    formatted = layout(text, file)
    if _without_spans(parse_text(formatted, file)) != _without_spans(original):
        raise FormatError(f"{file}: formatting would change the model's meaning (a bug in the formatter)")
    return formatted
