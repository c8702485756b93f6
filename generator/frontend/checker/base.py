"""The checker's core: the state every rule fills in, the driver that runs
the rules in order, names and their look-up, types, expressions and
constants, and the helpers the rules share."""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path as FsPath

from ...core.impl_files import ImplFileError, split_impl
from ...core.source import Diagnostics, Span, did_you_mean, note
from ...core import types as T
from .. import ast
from ..expressions import ExprTyper, Symbol
from ..model import (ChannelInfo, ChartInfo, CheckedModel, Claim, ConstInfo, DataflowInfo, DataInfo, DeviceDatum,
                     InterfaceInfo, PrimitiveDevice, RemoteInfo, TaskInfo)

_KIND_NAMES = {
    ast.Const: "const", ast.Channel: "channel", ast.DeviceType: "device type",
    ast.DeviceInstance: "device", ast.ActorType: "actor type", ast.Dataflow: "dataflow",
    ast.Chart: "chart", ast.Task: "task", ast.NodeDecl: "node", ast.LinkDecl: "link",
}
MAX_RATE = 65535
# Names an actor's C code cannot see under their own name (docs/language.md §5).
C_RESERVED = frozenset("""
    auto break case char const continue default do double else enum extern float for goto if inline int long
    register restrict return short signed sizeof static struct switch typedef union unsigned void volatile while
    _Bool _Complex _Imaginary bool true false int8_t uint8_t int16_t uint16_t int32_t uint32_t int64_t uint64_t
    size_t NULL main
""".split())


def with_article(noun: str) -> str:
    """``noun`` with its indefinite article: 'a var', 'an actor type'."""
    return f"{'an' if noun[:1] in 'aeiou' else 'a'} {noun}"


def kind_name(decl) -> str:
    if isinstance(decl, ast.Data):
        return decl.kind
    return _KIND_NAMES.get(type(decl), "declaration")



class CheckerBase:
    """The checker's state and the rules every other rule builds on; the
    rules themselves are the mixins composed in :class:`Checker`
    (checker/__init__.py)."""

    def __init__(self, modules: list[ast.Module], root: ast.Module, diags: Diagnostics):
        self.modules = modules
        self.root = root
        self.diags = diags
        self.globals: dict[str, ast.Named] = {}
        self.consts: dict[str, ConstInfo] = {}
        self.data: dict[str, DataInfo] = {}
        self.channels: dict[str, ChannelInfo] = {}
        self.device_types: dict[str, ast.DeviceType] = {}
        self.actor_types: dict[str, ast.ActorType] = {}
        self.actor_costs: dict[str, int] = {}  # ns per firing, by actor type
        self.actor_type_files: dict[str, str] = {}
        self.declaration_files: dict[int, str] = {}  # id(declaration) -> its file (handler files are relative to it)
        self.devices: list[PrimitiveDevice] = []
        self.device_data: dict[str, DeviceDatum] = {}
        self.top_devices: dict[str, ast.DeviceInstance] = {}
        self.dataflows: dict[str, DataflowInfo] = {}
        self.charts: dict[str, ChartInfo] = {}
        self.tasks: dict[str, TaskInfo] = {}
        self.interfaces: list[InterfaceInfo] = []
        self.remote: RemoteInfo | None = None
        self.claims: list[Claim] = []
        self.nodes: dict = {}  # distribution (checker/nodes.py)
        self.links: dict = {}
        self.task_nodes: dict[str, str] = {}
        self.device_nodes: dict[str, str] = {}
        self._top_device_nodes: dict[str, str] = {}
        self.exports: list = []
        self._const_in_progress: list[str] = []
        self._const_failed: set[str] = set()
        self._addresses: dict[tuple[str, int, int], ast.Data] = {}  # (table, first, last) -> item

    # ================================================================ driver

    def run(self) -> CheckedModel | None:
        self.collect_names()
        for decl in self._decls(ast.Const):
            self.const_value(decl.name)
        for decl in self._decls(ast.NodeDecl):
            self.check_node(decl)
        for decl in self._decls(ast.LinkDecl):
            self.check_link(decl)
        for decl in self._decls(ast.Data):
            self.check_data(decl)
        for decl in self._decls(ast.Channel):
            self.check_channel(decl)
        for decl in self._decls(ast.ActorType):
            self.check_actor_type(decl)
        for decl in self._decls(ast.DeviceType):
            self.check_device_type(decl)
        for decl in self._decls(ast.DeviceInstance):
            self.elaborate_device(decl)
        for decl in self._decls(ast.Dataflow):
            self.check_dataflow(decl)
        for decl in self._decls(ast.Chart):
            self.check_chart(decl)
        for decl in self._decls(ast.Task):
            self.check_task(decl)
        self.check_run_once()
        self.check_writers()
        self.check_channels_connected()
        for module in self.modules:
            for iface in module.interfaces:
                self.check_interface(iface)
            for settings in module.remote:
                self.check_remote_settings(settings)
        self.check_placement()
        self.check_claims()
        if self.diags.has_errors:
            return None
        header = self.root.header
        return CheckedModel(
            name=header.name if header else FsPath(self.root.file).stem,
            title=header.title if header else None, file=self.root.file,
            consts=self.consts, data=self.data, channels=self.channels,
            device_types=self.device_types, devices=self.devices, device_data=self.device_data,
            top_devices=self.top_devices, actor_types=self.actor_types, dataflows=self.dataflows,
            charts=self.charts, tasks=self.tasks, interfaces=self.interfaces, claims=self.claims,
            actor_type_files=self.actor_type_files, actor_costs=self.actor_costs, nodes=self.nodes, links=self.links,
            task_nodes=self.task_nodes, device_nodes=self.device_nodes, exports=self.exports,
            remote=self.remote)

    def _decls(self, cls):
        for module in self.modules:
            for decl in module.declarations:
                if isinstance(decl, cls):
                    yield decl

    def error(self, span: Span, message: str, hint: str | None = None, notes=()) -> None:
        self.diags.error(span, message, hint, tuple(notes))

    def report_c_file(self, path: FsPath, blocks: tuple[str, ...], named_at: Span, what: str) -> None:
        """An error for what :func:`c_file_problem` finds in a C file the
        model names at ``named_at``: at its place in the file, with a note
        at the name."""
        found = c_file_problem(path, blocks)
        if found is None:
            return
        span, message = found
        if span is None:
            self.error(named_at, f"{what} {message}")
        else:
            self.error(span, message, notes=[note(named_at, f"the {what} is named here")])

    # ================================================================ names

    def collect_names(self) -> None:
        """One namespace for the model and its imports; a clash names both."""
        for module in self.modules:
            for decl in module.declarations:
                self.declaration_files[id(decl)] = module.file
                first = self.globals.get(decl.name)
                if first is not None:
                    self.error(decl.name_span, f"'{decl.name}' is already declared as {with_article(kind_name(first))}",
                               "give one of them another name",
                               [note(first.name_span, f"'{decl.name}' is first declared here")])
                    continue
                self.globals[decl.name] = decl
                if isinstance(decl, ast.DeviceType):
                    self.device_types[decl.name] = decl
                elif isinstance(decl, ast.ActorType):
                    self.actor_types[decl.name] = decl
                    self.actor_type_files[decl.name] = module.file

    def lookup(self, name: str, span: Span, wanted: tuple, what: str):
        """A global declaration of one of the ``wanted`` AST classes, or None (error given)."""
        decl = self.globals.get(name)
        if decl is None:
            candidates = [n for n, d in self.globals.items() if isinstance(d, wanted)]
            self.error(span, f"unknown {what} '{name}'", did_you_mean(name, candidates))
            return None
        if not isinstance(decl, wanted):
            self.error(span, f"'{name}' is {with_article(kind_name(decl))}, not {with_article(what)}",
                       notes=[note(decl.name_span, f"'{name}' is declared here")])
            return None
        return decl

    def resolve_type(self, ref: ast.TypeRef, type_params: dict[str, str | None] | None = None,
                     allow_string: bool = False):
        """A ValueType, a type parameter name (str), or None after an error."""
        if type_params and ref.name in type_params:
            return ref.name
        t = T.ALL_TYPES.get(ref.name)
        if t is None or (t is T.STRING and not allow_string):
            candidates = list(T.SCALARS) + list(type_params or ()) + (["string"] if allow_string else [])
            self.error(ref.span, f"unknown type '{ref.name}'", did_you_mean(ref.name, candidates))
            return None
        return t

    # ================================================================ expressions

    def global_symbol(self, path: ast.Path, allow=("const", "param", "var", "device_data")):
        """Resolve a path in the model's global scope to a Symbol or an error."""
        head = path.parts[0]
        decl = self.globals.get(head)
        if decl is None:
            candidates = [n for n, d in self.globals.items()
                          if isinstance(d, (ast.Const, ast.Data, ast.DeviceInstance))]
            return (f"unknown name '{head}'", did_you_mean(head, candidates))
        if isinstance(decl, ast.Const):
            if len(path.parts) > 1:
                return (f"'{head}' is a const and has no member '{path.parts[1]}'", None)
            info = self.const_value(head)
            if info is None:
                return Symbol("const", None, None, None, head)  # error reported already
            return Symbol("const", info.type, info.value, info, head)
        if isinstance(decl, ast.Data):
            if len(path.parts) > 1:
                return (f"'{head}' is a {decl.kind} and has no member '{path.parts[1]}'", None)
            if decl.kind not in allow:
                if "param" in allow:
                    return (f"'{head}' is a var; only consts and params can be given here", None)
                return (f"'{head}' is a {decl.kind}, known only at run time; a compile-time constant "
                        "is needed here", "use literals and consts here")
            info = self.data.get(head)
            return Symbol(decl.kind, info.type if info else None, None, info, head)
        if isinstance(decl, ast.DeviceInstance):
            if "device_data" not in allow:
                return (f"'{path.text}' is device data, known only at run time; a compile-time "
                        "constant is needed here", "use literals and consts here")
            datum = self.device_datum(path)
            if isinstance(datum, tuple):
                return datum
            if datum.port.direction != "out":
                return (f"'{path.text}' is a device input (application -> device) and cannot be read",
                        "read the var that drives it instead")
            return Symbol("device_data", datum.type, None, datum, path.text)
        return (f"'{head}' is {with_article(kind_name(decl))}, not a value", None)

    def typer(self, resolve, runtime=True, used=None, conversion_hint=None) -> ExprTyper:
        return ExprTyper(self.diags, resolve, runtime=runtime, symbols_used=used, conversion_hint=conversion_hint)

    def const_typer(self) -> ExprTyper:
        return self.typer(lambda p: self.global_symbol(p, allow=("const",)), runtime=False)

    # ================================================================ consts and data

    def const_value(self, name: str) -> ConstInfo | None:
        if name in self.consts:
            return self.consts[name]
        decl = self.globals.get(name)
        if not isinstance(decl, ast.Const):
            return None
        if name in self._const_failed:
            return None
        if name in self._const_in_progress:
            cycle = self._const_in_progress[self._const_in_progress.index(name):] + [name]
            self.error(decl.name_span, f"const '{name}' is defined in terms of itself"
                                       + (f" ({' -> '.join(cycle)})" if len(cycle) > 2 else ""))
            self._const_failed.update(cycle)
            return None
        self._const_in_progress.append(name)
        t = self.resolve_type(decl.type)
        info = None
        if t is not None:
            v = self.const_typer().expect_const(decl.value, t, f"const '{name}'")
            if v.type is not None and name not in self._const_failed:
                info = ConstInfo(decl, t, v.const)
                self.consts[name] = info
        self._const_in_progress.pop()
        if info is None:
            self._const_failed.add(name)
        return info



def claim_owner(c: Claim) -> str:
    if c.owner.startswith("link "):
        return f"link '{c.owner[5:]}'"
    return f"interface '{c.owner}'" if " " in c.owner or c.owner == "debug" else f"device '{c.owner}'"


def port_of(atype: ast.ActorType, name: str) -> ast.ActorPort:
    return next(p for p in atype.ports if p.name == name)


def sizing_params(atype: ast.ActorType) -> set[str]:
    """Parameters that rates or array sizes use: they must be constants."""
    names: set[str] = set()

    def walk(e):
        if isinstance(e, ast.Path):
            names.add(e.parts[0])
        elif isinstance(e, ast.Binary):
            walk(e.left)
            walk(e.right)
        elif isinstance(e, ast.Unary):
            walk(e.operand)

    for port in atype.ports:
        if port.rate is not None:
            walk(port.rate)
    for st in atype.states:
        if st.type.size is not None:
            walk(st.type.size)
    return names


def in_library(span: Span) -> bool:
    """Whether a span lies in a shipped library (``<std>``), which a user cannot edit."""
    return span.file.startswith("<")


def short_name(text: str, limit: int = 60) -> str:
    """``text`` cut to ``limit`` characters for a message."""
    return text if len(text) <= limit else text[:limit - 3] + "..."


def c_file_problem(path: FsPath, blocks: tuple[str, ...]) -> tuple[Span | None, str] | None:
    """What is wrong with a C file from the model's folder (an actor's
    ``impl`` file, a device's handler file) that can be seen without
    compiling it: not UTF-8, a block of the other kind of file (an
    ``EL_STEP`` among a device's handlers), a block given twice or never
    closed. (its place in the file, or None for the whole file; the
    message), or None."""
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        return None, "is not UTF-8 text"
    except (OSError, ValueError):
        return None  # missing_file says why
    try:
        split_impl(text, str(path), blocks)
    except ImplFileError as err:
        return Span(str(path), err.line, err.column, err.line, err.column + 1), err.message
    return None


def missing_file(path: FsPath) -> str | None:
    """Why the file a model names cannot be used ('not found', or the
    system's reason such as 'File name too long'), or None when it is a
    file: a bad name is a diagnostic, never an OSError out of the checker."""
    try:
        return None if path.is_file() else "not found"
    except (OSError, ValueError) as err:  # ValueError: an embedded NUL
        reason = getattr(err, "strerror", None) or str(err)
        return f"cannot be read: {reason[:1].lower()}{reason[1:]}"


def whole_ms(value) -> bool:
    return Fraction(value) % 1000 == 0


def whole_us(value) -> bool:
    return Fraction(value).denominator == 1


def show_value(value, t: T.ValueType) -> str:
    if t is T.TIME:
        us = Fraction(value)
        for unit, scale in (("s", 1_000_000), ("ms", 1000), ("us", 1)):
            if us % scale == 0:
                return f"{us // scale} {unit}"
        return f"{float(us)} us"
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, Fraction):
        return str(T.to_double(value))
    return str(value)
