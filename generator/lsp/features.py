"""What the language server says about a model, in plain Python terms:
hover texts, completion candidates, quick fixes and rename checks. The
server (server.py) turns these into protocol messages."""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from ..frontend import ast
from ..frontend.loader import library_path
from .index import Definition
from .workspace import Analysis, Workspace, file_path

NAME = re.compile(r"[A-Za-z_]\w*\Z")
DID_YOU_MEAN = re.compile(r"did you mean '([^']+)'\?")
UNKNOWN_TYPE = re.compile(r"unknown (?:actor|device) type '(\w+)'")


# ---------------------------------------------------------------- hover

def hover_text(workspace: Workspace, analysis: Analysis, definition: Definition) -> str:
    """Markdown describing a declared name."""
    node = definition.node
    lines = [f"**{definition.kind}** `{node.name}`"]
    if isinstance(node, ast.Data):
        lines += _data_lines(workspace, analysis, node)
    elif isinstance(node, ast.Instance):
        lines += _instance_lines(workspace, analysis, node, definition)
    elif isinstance(node, ast.DeviceInstance):
        lines += _device_lines(workspace, analysis, node)
    elif isinstance(node, (ast.ActorType, ast.DeviceType)):
        doc = doc_comment(workspace, node)
        lines += [f"```elab\n{signature(workspace, node)}\n```"] + ([doc] if doc else [])
    else:
        lines.append(f"```elab\n{signature(workspace, node)}\n```")
    return "\n\n".join(lines)


def _data_lines(workspace: Workspace, analysis: Analysis, node: ast.Data) -> list[str]:
    info = analysis.result.model.data.get(node.name) if analysis.result.model else None
    out = [f"type: `{info.type.name if info else node.type.name}`"]
    if node.range is not None:
        out.append(f"range: `{workspace.source(node.range.low.span)}..{workspace.source(node.range.high.span)}`")
    if node.unit:
        out.append(f"unit: \"{node.unit}\"")
    if node.scale is not None:
        out.append(f"scale: {float(node.scale):g} (engineering value = stored value x scale)")
    out.append(f"default: `{workspace.source(node.default.span)}`" if node.default is not None
               else "default: zero")
    return out


def _instance_lines(workspace: Workspace, analysis: Analysis, node: ast.Instance,
                    definition: Definition) -> list[str]:
    actor = analysis.index.globals.get(node.type_name)
    type_args = f"<{', '.join(t.name for t in node.type_args)}>" if node.type_args else ""
    out = [f"actor: `{node.type_name}{type_args}`"]
    info = None
    if analysis.result.model is not None and definition.scope is not None:
        flow = analysis.result.model.dataflows.get(definition.scope.name)
        info = flow.instances.get(node.name) if flow else None
    if actor is not None and isinstance(actor.node, ast.ActorType):
        ports = []
        for port in actor.node.ports:
            if info is not None:
                shown = f"{info.port_types[port.name].name}, rate {info.port_rates[port.name]}"
            else:
                rate = workspace.source(port.rate.span) if port.rate is not None else "1"
                shown = f"{port.type.name}, rate {rate}"
            ports.append(f"- {port.direction} `{port.name}`: {shown}")
        params = ", ".join(f"{p.name}: {p.type.name}" for p in actor.node.params)
        out += [f"parameters: {params or 'none'}", "ports:\n" + "\n".join(ports)]
    return out


def _device_lines(workspace: Workspace, analysis: Analysis, node: ast.DeviceInstance) -> list[str]:
    out = [f"type: `{node.type_name}`"]
    model = analysis.result.model
    if model is not None:
        primitives = [d for d in model.devices if d.path == node.name or d.path.startswith(node.name + ".")]
        for dev in primitives:
            data = ", ".join(f"{p.direction} {p.name}: {p.type.name}" for p in dev.ports.values())
            claims = ", ".join(str(c) for c in dev.claims) or "none"
            out.append(f"`{dev.path}`: driver `{dev.driver}`; data: {data or 'none'}; claims: {claims}")
        return out
    device_type = analysis.index.globals.get(node.type_name)
    if device_type is not None and isinstance(device_type.node, ast.DeviceType):
        t = device_type.node
        out.append(f"driver: `{t.driver}`" if t.driver else "parts: " + ", ".join(p.name for p in t.parts))
        out.append("data: " + (", ".join(f"{p.direction} {p.name}: {p.type.name}" for p in t.ports) or "none"))
        out.append("claims: " + (", ".join(workspace.source(c.span) for c in t.claims) or "none"))
    return out


def signature(workspace: Workspace, node: ast.Named) -> str:
    """The first line of a declaration, without an opening brace."""
    first = workspace.source(node.span).split("\n")[0]
    return first.rstrip(" {")


def doc_comment(workspace: Workspace, node: ast.Named) -> str:
    """The ``//`` comment lines just above a declaration."""
    lines = workspace.text(file_path(node.span.file)).split("\n")
    doc: list[str] = []
    i = node.span.line - 2
    while i >= 0 and lines[i].lstrip().startswith("//"):
        doc.insert(0, lines[i].lstrip()[2:].strip())
        i -= 1
    return " ".join(doc)


# ---------------------------------------------------------------- rename

def rename_problem(analysis: Analysis, definition: Definition, new_name: str) -> str | None:
    """Why ``definition`` cannot be renamed to ``new_name``, or None."""
    from .completion import KEYWORDS

    if not NAME.match(new_name) or new_name in KEYWORDS:
        return f"'{new_name}' is not a name"
    if any(o.span.file.startswith("<") for o in analysis.index.references(definition)):
        return f"'{definition.name}' is declared in a library shipped with easylab"
    if new_name != definition.name and new_name in analysis.index.names_in_scope_of(definition):
        return f"'{new_name}' is already a name where '{definition.name}' is used"
    return None


# ---------------------------------------------------------------- quick fixes

@dataclass(frozen=True)
class QuickFix:
    """Replace ``old`` by ``new`` where the diagnostic points (``insert_line``:
    insert ``new`` as a line before that 1-based line instead)."""

    title: str
    old: str
    new: str
    insert_line: int | None = None


def quick_fixes(workspace: Workspace, path: Path, message: str, hint: str | None,
                covered: str) -> list[QuickFix]:
    """The fixes for one diagnostic (its message, hint and the text it covers)."""
    fixes = []
    quoted = re.search(r"'([^']+)'", message)
    suggestion = DID_YOU_MEAN.search(hint or "")
    if quoted and suggestion and quoted.group(1) in covered:
        fixes.append(QuickFix(f"Change '{quoted.group(1)}' to '{suggestion.group(1)}'",
                              quoted.group(1), suggestion.group(1)))
    unknown = UNKNOWN_TYPE.search(message)
    if unknown and unknown.group(1) in std_names() and not _imports_std(workspace.text(path)):
        fixes.append(QuickFix("Add 'import std'", "", "import std", insert_line=_import_line(workspace.text(path))))
    return fixes


def _imports_std(text: str) -> bool:
    return re.search(r"^\s*import\s+std\b", text, re.M) is not None


def _import_line(text: str) -> int:
    """Where an import goes: after the model header, else at the top."""
    for i, line in enumerate(text.split("\n")):
        if re.match(r"\s*model\b", line):
            return i + 2
    return 1


_STD: dict[str, ast.Named] = {}


def std_declarations() -> dict[str, ast.Named]:
    """The std library's declarations by name (parsed once)."""
    if not _STD:
        from ..frontend.parser import parse_text

        module = parse_text(library_path("std").read_text(encoding="utf-8"), "<std>")
        _STD.update({d.name: d for d in module.declarations})
    return _STD


def std_names() -> set[str]:
    return set(std_declarations())
