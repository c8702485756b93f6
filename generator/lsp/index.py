"""Where each name of a model is declared and where it is used.

The index is built from the parsed modules of a model (the root file and
its imports, std.elab included) by the scoping rules of docs/language.md:
one global namespace for every file; inside a dataflow its actor
instances, inside a chart its steps, inside an actor or device type its
type parameters, parameters, ports, parts and state. It serves document
symbols, go to definition, find references, rename and hover; it needs no
checked model, so it works while the model still has errors.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

from ..core.source import Span
from ..frontend import ast
from ..frontend.checker import kind_name


# The names the checker has no word for: those inside a dataflow, a chart or a type.
LOCAL_KINDS = {ast.Instance: "actor instance", ast.Step: "step", ast.FormalParam: "parameter",
               ast.ActorPort: "port", ast.DataPort: "port", ast.StateVar: "state variable",
               ast.TypeParam: "type parameter", ast.Part: "part"}


def name_kind(node: ast.Named) -> str:
    """What a declared name is, in words: 'param', 'actor instance', 'port'."""
    return LOCAL_KINDS.get(type(node)) or kind_name(node)


@dataclass(eq=False)
class Definition:
    """A declared name: its node, and the scope it belongs to (None: global)."""

    node: ast.Named
    kind: str
    scope: ast.Named | None = None
    members: dict[str, "Definition"] = field(default_factory=dict)  # a type's or block's own names

    @property
    def name(self) -> str:
        return self.node.name

    @property
    def span(self) -> Span:
        return self.node.name_span


@dataclass(frozen=True)
class Occurrence:
    """One place a name is written, and the definition it means."""

    span: Span
    definition: Definition


class ModelIndex:
    """The definitions and occurrences of every name in ``modules``."""

    def __init__(self, modules: list[ast.Module]):
        self.modules = modules
        self.globals: dict[str, Definition] = {}
        self.occurrences: list[Occurrence] = []
        self.scopes: dict[int, dict[str, Definition]] = {}  # id(scope node) -> its names
        for module in modules:
            for decl in module.declarations:
                if decl.name not in self.globals:  # a clash: the checker reports it, the first one counts
                    self.globals[decl.name] = self._define(decl, None)
        for definition in list(self.globals.values()):  # a type's own names, before any use of them
            self._define_members(definition)
        for module in modules:
            for decl in module.declarations:
                self._walk_declaration(decl)
            for export in module.exports:
                self._use(export.name, export.name_span, None)
                self._walk_paths(export.link, None)

    # ---------------------------------------------------------------- queries

    def at(self, file: str, line: int, column: int) -> Occurrence | None:
        """The occurrence under a position (1-based line and column)."""
        for occ in self.occurrences:
            s = occ.span
            if s.file == file and s.line == line and s.column <= column <= s.end_column and s.end_line == line:
                return occ
        return None

    def references(self, definition: Definition) -> list[Occurrence]:
        """Every occurrence of ``definition``, its declaration included."""
        return [o for o in self.occurrences if o.definition is definition]

    def names_in_scope_of(self, definition: Definition) -> set[str]:
        """The names a new name for ``definition`` must not take: those of its
        own scope, and for a global those of every scope that uses it."""
        if definition.scope is not None:
            return set(self.scopes.get(id(definition.scope), {})) | set(self.globals)
        taken = set(self.globals)
        for occ in self.references(definition):
            for names in self._scopes_around(occ.span):
                taken |= names
        return taken

    def _scopes_around(self, span: Span):
        for module in self.modules:
            for decl in module.declarations:
                if id(decl) in self.scopes and _inside(span, decl.span):
                    yield set(self.scopes[id(decl)])

    # ---------------------------------------------------------------- building

    def _define(self, node: ast.Named, scope: ast.Named | None, kind: str | None = None) -> Definition:
        definition = Definition(node, kind or name_kind(node), scope)
        self.occurrences.append(Occurrence(node.name_span, definition))
        if scope is not None:
            self.scopes.setdefault(id(scope), {})[node.name] = definition
        return definition

    def _use(self, name: str, span: Span, scope: dict[str, Definition] | None) -> Definition | None:
        definition = (scope or {}).get(name) or self.globals.get(name)
        if definition is not None:
            self.occurrences.append(Occurrence(span, definition))
        return definition

    def _member(self, owner: Definition | None, name: str, span: Span) -> None:
        """A use of a type's own name (a parameter, a port) through an instance of it."""
        if owner is not None and name in owner.members:
            self.occurrences.append(Occurrence(span, owner.members[name]))

    def _type_of(self, type_name: str) -> Definition | None:
        return self.globals.get(type_name)

    def _walk_paths(self, node, scope: dict[str, Definition] | None) -> None:
        """Uses of names in every dotted name inside ``node``."""
        for path in _paths(node):
            first = self._use(path.parts[0], path.part_spans[0], scope)
            if first is not None and len(path.parts) > 1:
                self._member(self._instance_type(first), path.parts[1], path.part_spans[1])

    def _instance_type(self, definition: Definition) -> Definition | None:
        node = definition.node
        if isinstance(node, (ast.Instance, ast.DeviceInstance, ast.Part)):
            return self._type_of(node.type_name)
        return None

    def _actuals(self, type_def: Definition | None, args: tuple[ast.Actual, ...], scope) -> None:
        for arg in args:
            self._member(type_def, arg.name, arg.name_span)
            self._walk_paths(arg.value, scope)

    def _define_members(self, owner: Definition) -> None:
        decl = owner.node
        if isinstance(decl, (ast.ActorType, ast.DeviceType)):
            for member in (*getattr(decl, "type_params", ()), *decl.params, *decl.ports, *decl.states,
                           *getattr(decl, "parts", ())):
                owner.members[member.name] = self._define(member, decl)

    def _walk_declaration(self, decl: ast.Named) -> None:
        own = self.globals.get(decl.name)
        if own is None or own.node is not decl:  # a second declaration of a name: its own names still count
            self._define_members(Definition(decl, name_kind(decl)))
        if isinstance(decl, (ast.ActorType, ast.DeviceType)):
            scope = self.scopes.get(id(decl), {})
            for member in (*decl.params, *decl.ports):
                self._walk_paths(member, scope)
            if isinstance(decl, ast.DeviceType):
                for part in decl.parts:
                    part_type = self._use(part.type_name, part.type_span, None)
                    self._actuals(part_type, part.args, scope)
                for export in decl.exports:
                    self._walk_paths(export.target, scope)
                self._walk_paths(decl.claims, scope)
        elif isinstance(decl, ast.Dataflow):
            for inst in decl.instances:
                self._define(inst, decl)
            scope = self.scopes.get(id(decl), {})
            for inst in decl.instances:
                inst_type = self._use(inst.type_name, inst.type_span, None)
                self._actuals(inst_type, inst.args, scope)
            self._walk_paths(decl.edges, scope)
        elif isinstance(decl, ast.Chart):
            for step in decl.steps:
                self._define(step, decl)
            scope = self.scopes.get(id(decl), {})
            for step in decl.steps:
                self._walk_paths((step.entry, step.exit), scope)
                for run in step.runs:
                    self._use(run.name, run.name_span, None)
            for transition in decl.transitions:
                for ref in (*transition.sources, *transition.targets):
                    self._use(ref.name, ref.name_span, scope)
                self._walk_paths(transition.guard, scope)
        elif isinstance(decl, ast.DeviceInstance):
            device_type = self._use(decl.type_name, decl.type_span, None)
            self._actuals(device_type, decl.args, None)
            self._placement(decl.node)
            for safe in decl.safe:
                self._member(device_type, safe.datum.parts[0], safe.datum.part_spans[0])
                self._walk_paths(safe.value, None)
        elif isinstance(decl, ast.Task):
            for run in decl.runs:
                self._use(run.name, run.name_span, None)
            self._walk_paths(decl.attrs, None)
            self._placement(decl.node)
        elif isinstance(decl, ast.Channel):
            self._walk_paths(decl.delay, None)
            self._placement(decl.over)
        elif isinstance(decl, ast.LinkDecl):
            for member in decl.members:
                self._use(member.node, member.node_span, None)
            self._walk_paths((decl.attrs, tuple(m.attrs for m in decl.members)), None)
        else:  # consts, params and vars: their values and ranges
            self._walk_paths(decl, None)

    def _placement(self, placement: ast.Placement | None) -> None:
        if placement is not None:
            self._use(placement.name, placement.name_span, None)


def _inside(span: Span, outer: Span) -> bool:
    return (span.file == outer.file and (outer.line, outer.column) <= (span.line, span.column)
            and (span.end_line, span.end_column) <= (outer.end_line, outer.end_column))


def _paths(node):
    """Every :class:`ast.Path` inside an AST node (or tuple of them)."""
    stack = [node]
    while stack:
        item = stack.pop()
        if isinstance(item, ast.Path):
            yield item
        elif isinstance(item, tuple):
            stack.extend(reversed(item))
        elif dataclasses.is_dataclass(item) and not isinstance(item, Span):
            stack.extend(getattr(item, f.name) for f in reversed(dataclasses.fields(item)))


# ---------------------------------------------------------------- document symbols

SYMBOL_KINDS = {ast.DeviceInstance: "device", ast.DeviceType: "device type", ast.ActorType: "actor type",
                ast.Dataflow: "dataflow", ast.Chart: "chart", ast.Task: "task", ast.Data: "data",
                ast.Const: "const", ast.Channel: "channel", ast.NodeDecl: "node", ast.LinkDecl: "link"}


def outline(module: ast.Module) -> list[tuple[ast.Named, list[ast.Named]]]:
    """A file's declarations, each with its children: a dataflow's
    instances, a chart's steps, a type's ports and parts."""
    out = []
    for decl in module.declarations:
        if isinstance(decl, ast.Dataflow):
            children = list(decl.instances)
        elif isinstance(decl, ast.Chart):
            children = list(decl.steps)
        elif isinstance(decl, (ast.ActorType, ast.DeviceType)):
            children = [*decl.params, *decl.ports, *getattr(decl, "parts", ())]
        else:
            children = []
        out.append((decl, children))
    return out
