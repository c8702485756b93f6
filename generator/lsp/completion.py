"""Completion candidates: the language's keywords, the actor and device
types in scope with their parameters, the names that may stand on either
side of ``->`` in a dataflow, and the pins and UARTs of the boards the
model names (``node N board B [mcu M]``)."""

from __future__ import annotations

import functools
import re
from dataclasses import dataclass

from ..frontend import ast
from ..frontend.grammar import grammar_text
from .workspace import Analysis

# Every keyword is a quoted word of the grammar.
KEYWORDS = frozenset(w for w in re.findall(r'"([a-z][a-z_-]*)"', grammar_text()) if re.fullmatch(r"[a-z_]+", w))

PIN_CONTEXT = re.compile(r'pin\s*\[\s*"?(\w*)\Z')
MEMBER_CONTEXT = re.compile(r"([A-Za-z_]\w*)\.(\w*)\Z")


@dataclass(frozen=True)
class Candidate:
    """One completion: its label, what kind of thing it is, a short detail,
    and the text to insert (a snippet with ``${n:...}`` placeholders)."""

    label: str
    kind: str  # keyword | actor type | device type | data | port | instance | pin | uart | name
    detail: str = ""
    snippet: str | None = None


def candidates(analysis: Analysis | None, line_prefix: str, line: int, file: str) -> list[Candidate]:
    """What may be written at a position whose line starts with ``line_prefix``."""
    pins = PIN_CONTEXT.search(line_prefix)
    if pins:
        return [Candidate(p, "pin", f"pin of {b}") for b, p in _board_pins(analysis)]
    if analysis is None:
        return [Candidate(k, "keyword") for k in sorted(KEYWORDS)]
    index = analysis.index
    flow = _enclosing(analysis, ast.Dataflow, file, line)
    member = MEMBER_CONTEXT.search(line_prefix)
    if member:
        return _members(analysis, flow, member.group(1), line_prefix)
    if flow is not None:
        return _edge_ends(analysis, flow, "->" in line_prefix)
    out = [Candidate(k, "keyword") for k in sorted(KEYWORDS)]
    for name, definition in sorted(index.globals.items()):
        node = definition.node
        if isinstance(node, ast.ActorType):
            out.append(Candidate(name, "actor type", _params(node), _call_snippet(node)))
        elif isinstance(node, ast.DeviceType):
            out.append(Candidate(name, "device type", _params(node), _call_snippet(node)))
        else:
            out.append(Candidate(name, "name", definition.kind))
    out += [Candidate(f"uart{n}", "uart", f"UART {n} of {b}: {', '.join(pins)}") for b, n, pins in _board_uarts(analysis)]
    return out


def _params(node: ast.ActorType | ast.DeviceType) -> str:
    return "(" + ", ".join(f"{p.name}: {p.type.name}" for p in node.params) + ")"


def _call_snippet(node: ast.ActorType | ast.DeviceType) -> str:
    """``Gain<${1:T}>(k = ${2})``: the type's parameters as placeholders."""
    n = 0
    parts = [node.name]
    type_params = getattr(node, "type_params", ())
    if type_params:
        holes = []
        for tp in type_params:
            n += 1
            holes.append(f"${{{n}:{tp.name}}}")
        parts.append("<" + ", ".join(holes) + ">")
    args = []
    for p in node.params:
        n += 1
        args.append(f"{p.name} = ${{{n}}}")
    parts.append("(" + ", ".join(args) + ")")
    return "".join(parts)


def _enclosing(analysis: Analysis, cls, file: str, line: int):
    for module in analysis.modules:
        if module.file != file:
            continue
        for decl in module.declarations:
            if isinstance(decl, cls) and decl.span.line <= line <= decl.span.end_line:
                return decl
    return None


def _ports(analysis: Analysis, type_name: str, direction: str | None) -> list[ast.Named]:
    definition = analysis.index.globals.get(type_name)
    if definition is None or not isinstance(definition.node, (ast.ActorType, ast.DeviceType)):
        return []
    return [p for p in definition.node.ports if direction is None or p.direction == direction]


def _edge_ends(analysis: Analysis, flow: ast.Dataflow, after_arrow: bool) -> list[Candidate]:
    """Before ``->`` what gives tokens (out ports, a device's out data,
    params, vars, channels); after it what takes them (in ports, a
    device's in data, vars, channels: a param is written by no edge)."""
    out = []
    want = "in" if after_arrow else "out"
    for inst in flow.instances:
        for port in _ports(analysis, inst.type_name, want):
            out.append(Candidate(f"{inst.name}.{port.name}", "port", f"{port.direction} {port.type.name}"))
    for name, definition in sorted(analysis.index.globals.items()):
        node = definition.node
        if isinstance(node, ast.DeviceInstance):
            # a device's `in` data is written by the model, its `out` data read
            for port in _ports(analysis, node.type_name, "in" if after_arrow else "out"):
                out.append(Candidate(f"{name}.{port.name}", "port", f"device data, {port.type.name}"))
        elif isinstance(node, ast.Channel) or (isinstance(node, ast.Data)
                                                and not (after_arrow and node.kind == "param")):
            out.append(Candidate(name, "data", definition.kind))
    return out


def _members(analysis: Analysis, flow: ast.Dataflow | None, owner: str, prefix: str) -> list[Candidate]:
    scope = analysis.index.scopes.get(id(flow), {}) if flow is not None else {}
    definition = scope.get(owner) or analysis.index.globals.get(owner)
    if definition is None or not isinstance(definition.node, (ast.Instance, ast.DeviceInstance)):
        return []
    direction = None
    if flow is not None and isinstance(definition.node, ast.Instance):
        direction = "in" if "->" in prefix else "out"
    return [Candidate(p.name, "port", f"{p.direction} {p.type.name}")
            for p in _ports(analysis, definition.node.type_name, direction)]


def _boards(analysis: Analysis | None) -> list[tuple[str, str | None]]:
    if analysis is None:
        return []
    return sorted({(d.node.board, d.node.mcu) for d in analysis.index.globals.values()
                   if isinstance(d.node, ast.NodeDecl)}, key=str)


@functools.lru_cache(maxsize=16)
def _board_part(board: str, mcu: str | None):
    """A board's MCU resources (None: unknown board, or none to claim)."""
    from ..board.registry import load_board
    from ..core.errors import BuildError

    try:
        mcu_part = load_board(board).configure(mcu).part
    except (BuildError, OSError, KeyError, ValueError):
        return None
    return mcu_part.part() if mcu_part is not None else None


def _board_pins(analysis: Analysis | None) -> list[tuple[str, str]]:
    out = []
    for board, mcu in _boards(analysis):
        part = _board_part(board, mcu)
        out += [(board, pin) for pin in (part.pins if part else [])]
    return out


def _board_uarts(analysis: Analysis | None) -> list[tuple[str, int, list[str]]]:
    out = []
    for board, mcu in _boards(analysis):
        part = _board_part(board, mcu)
        out += [(board, n, pins) for n, pins in sorted((part.uart if part else {}).items())]
    return out
