"""The checker: names, types, constants, writers, resources and chart structure.

It walks the AST of a model and its imports once per concern, collecting
every error it finds (one run reports all of them), and on success returns
the :class:`~easylab.model.CheckedModel`. The rules are those of
docs/language.md; each error names the rule it enforces.
"""

from __future__ import annotations

import re
from fractions import Fraction
from pathlib import Path as FsPath

from . import ast
from . import types as T
from .expressions import ERROR, ExprTyper, Symbol, Value
from .model import (ActionInfo, ActorInstanceInfo, ArgValue, ChannelInfo, ChartInfo, CheckedModel, Claim, ConstInfo,
                    DataflowInfo, DataInfo, DeviceDatum, DevicePort, EdgeInfo, Endpoint, InterfaceInfo,
                    PrimitiveDevice, StepInfo, TaskInfo, TransitionInfo, Writer)
from .source import Diagnostics, Span, closest, did_you_mean, note

_KIND_NAMES = {
    ast.Const: "const", ast.Channel: "channel", ast.DeviceType: "device type",
    ast.DeviceInstance: "device", ast.ActorType: "actor type", ast.Dataflow: "dataflow",
    ast.Chart: "chart", ast.Task: "task",
}
_MAX_RATE = 65535
# Names an actor's C code cannot see under their own name (docs/language.md §5).
C_RESERVED = frozenset("""
    auto break case char const continue default do double else enum extern float for goto if inline int long
    register restrict return short signed sizeof static struct switch typedef union unsigned void volatile while
    _Bool _Complex _Imaginary bool true false int8_t uint8_t int16_t uint16_t int32_t uint32_t int64_t uint64_t
    size_t NULL main
""".split())


def _a(noun: str) -> str:
    """``noun`` with its indefinite article: 'a var', 'an actor type'."""
    return f"{'an' if noun[:1] in 'aeiou' else 'a'} {noun}"


def kind_name(decl) -> str:
    if isinstance(decl, ast.Data):
        return decl.kind
    return _KIND_NAMES.get(type(decl), "declaration")


class Checker:
    """Checks one loaded model; see :func:`check`."""

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
        self.actor_type_files: dict[str, str] = {}
        self.devices: list[PrimitiveDevice] = []
        self.device_data: dict[str, DeviceDatum] = {}
        self.top_devices: dict[str, ast.DeviceInstance] = {}
        self.dataflows: dict[str, DataflowInfo] = {}
        self.charts: dict[str, ChartInfo] = {}
        self.tasks: dict[str, TaskInfo] = {}
        self.interfaces: list[InterfaceInfo] = []
        self.claims: list[Claim] = []
        self._const_in_progress: list[str] = []
        self._const_failed: set[str] = set()
        self._addresses: dict[tuple[str, int, int], ast.Data] = {}  # (table, first, last) -> item

    # ================================================================ driver

    def run(self) -> CheckedModel | None:
        self.collect_names()
        for decl in self._decls(ast.Const):
            self.const_value(decl.name)
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
            actor_type_files=self.actor_type_files)

    def _decls(self, cls):
        for module in self.modules:
            for decl in module.declarations:
                if isinstance(decl, cls):
                    yield decl

    def error(self, span: Span, message: str, hint: str | None = None, notes=()) -> None:
        self.diags.error(span, message, hint, tuple(notes))

    # ================================================================ names

    def collect_names(self) -> None:
        """One namespace for the model and its imports; a clash names both."""
        for module in self.modules:
            for decl in module.declarations:
                first = self.globals.get(decl.name)
                if first is not None:
                    self.error(decl.name_span, f"'{decl.name}' is already declared as {_a(kind_name(first))}",
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
            self.error(span, f"'{name}' is {_a(kind_name(decl))}, not {_a(what)}",
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
        return (f"'{head}' is {_a(kind_name(decl))}, not a value", None)

    def typer(self, resolve, runtime=True, used=None) -> ExprTyper:
        return ExprTyper(self.diags, resolve, runtime=runtime, symbols_used=used)

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

    def check_data(self, decl: ast.Data) -> None:
        t = self.resolve_type(decl.type)
        if t is None:
            return
        if decl.type.size is not None:
            self.error(decl.type.span, f"a {decl.kind} is a scalar; arrays are for actor state only")
            return
        typer = self.const_typer()
        initial = 0 if t is not T.BOOL else False
        if t in (T.FLOAT32, T.TIME):
            initial = Fraction(0)
        if decl.default is not None:
            v = typer.expect_const(decl.default, t, f"the initial value of {decl.kind} '{decl.name}'")
            if v.type is not None:
                initial = v.const
        rng = None
        if decl.range is not None:
            if t is T.BOOL:
                self.error(decl.range.span, f"a range needs a number or time, and '{decl.name}' is a bool")
            else:
                lo = typer.expect_const(decl.range.low, t, "the range's lower bound")
                hi = typer.expect_const(decl.range.high, t, "the range's upper bound")
                if lo.type is not None and hi.type is not None:
                    rng = (lo.const, hi.const)
                    if lo.const > hi.const:
                        self.error(decl.range.span, f"empty range: {_show(lo.const, t)} is above {_show(hi.const, t)}")
                    elif not lo.const <= initial <= hi.const:
                        span = decl.default.span if decl.default is not None else decl.name_span
                        self.error(span, f"the initial value {_show(initial, t)} of '{decl.name}' is outside "
                                         f"its range {_show(lo.const, t)}..{_show(hi.const, t)}",
                                   None if decl.default is not None else "give an initial value inside the range")
        if t is T.TIME and not _whole_ms(initial):
            self.error(decl.default.span, "a run-time 'time' value counts whole milliseconds")
        if decl.persist and decl.kind != "param":
            span = dict(decl.attr_spans).get("persist", decl.span)
            self.error(span, "only params can be 'persist'", "make it a param, or drop 'persist'")
        if decl.service is not None and decl.service.address is not None and not 0 <= decl.service.address <= 65535:
            self.error(decl.service.span, f"register address {decl.service.address} is outside 0..65535")
        elif decl.service is not None and decl.service.address is not None:
            # Items clash when their registers overlap in the same table.
            table = T.register_table(t, decl.service.access)
            first = decl.service.address
            last = first + T.register_count(t) - 1
            for (other_table, other_first, other_last), other in self._addresses.items():
                if other_table == table and first <= other_last and other_first <= last:
                    where = f"{first}" if first == last else f"{first}..{last}"
                    self.error(decl.service.span, f"{table} register {where} of '{decl.name}' overlaps "
                                                  f"'{other.name}' ({other_first}..{other_last})"
                                                  if other_last != other_first or first != last else
                               f"{table} register {first} is given to '{other.name}' and to '{decl.name}'",
                               "give each item its own address, or leave the address out to have one assigned",
                               [note(other.service.span, f"'{other.name}' has it here")])
                    break
            else:
                self._addresses[(table, first, last)] = decl
        self.data[decl.name] = DataInfo(decl, t, initial, rng)

    def check_channel(self, decl: ast.Channel) -> None:
        t = self.resolve_type(decl.type)
        if t is None:
            return
        tokens = self.delay_tokens(decl.delay, t) if decl.delay else ()
        self.channels[decl.name] = ChannelInfo(decl, t, tokens)

    def delay_tokens(self, delay: ast.Delay, t: T.ValueType) -> tuple:
        """The initial tokens a ``delay`` gives: a count of zeros, or a list."""
        typer = self.const_typer()
        if delay.values is not None:
            values = []
            for e in delay.values:
                v = typer.expect_const(e, t, "an initial token")
                values.append(v.const if v.type is not None else 0)
            return tuple(values)
        v = typer.expect_const(delay.count, None, "a delay")
        if v.type is None:
            return ()
        if not (v.type.is_integer and v.type is not T.TIME) or v.const < 0:
            self.error(delay.count.span, "a delay is a count of initial tokens: a non-negative integer",
                       "for initial values other than zero, write a list: delay [1, 2]")
            return ()
        if v.const > 1_000_000:
            self.error(delay.count.span, f"a delay of {v.const} tokens is more than this tool supports (1000000)")
            return ()
        zero = False if t is T.BOOL else 0
        return (zero,) * v.const

    # ================================================================ actor types

    def check_actor_type(self, decl: ast.ActorType) -> None:
        seen: dict[str, Span] = {}

        def unique(name: str, span: Span, what: str) -> None:
            if name in seen:
                self.error(span, f"'{name}' is declared twice in actor type '{decl.name}'",
                           notes=[note(seen[name], "first declared here")])
            else:
                seen[name] = span
            if name in C_RESERVED or name.lower().startswith("el_"):
                self.error(span, f"{what} '{name}' of actor type '{decl.name}' cannot be named like that: "
                                 "the actor's C code sees it under its own name",
                           "C keywords, C type names and names starting with el_ are reserved")

        tparams = {}
        for tp in decl.type_params:
            unique(tp.name, tp.name_span, "type parameter")
            if tp.name in T.ALL_TYPES:
                self.error(tp.name_span, f"type parameter '{tp.name}' hides the type of that name")
            if tp.bound is not None and tp.bound not in T.BOUNDS:
                self.error(tp.span, f"unknown type bound '{tp.bound}'",
                           did_you_mean(tp.bound, T.BOUNDS) or "bounds are 'number' and 'integer'")
            tparams[tp.name] = tp.bound
        for p in decl.params:
            unique(p.name, p.name_span, "parameter")
            self.resolve_type(p.type, tparams, allow_string=True)
        for port in decl.ports:
            unique(port.name, port.name_span, "port")
            self.resolve_type(port.type, tparams)
            if port.type.size is not None:
                self.error(port.type.span, "a port carries scalars; use 'rate n' for several tokens per firing")
        for st in decl.states:
            unique(st.name, st.name_span, "state")
            self.resolve_type(st.type, tparams)
        kinds: dict[str, Span] = {}
        for block in decl.code:
            if block.kind in kinds:
                self.error(block.span, f"actor type '{decl.name}' has two '{block.kind}' blocks",
                           notes=[note(kinds[block.kind], "the first is here")])
            kinds[block.kind] = block.span
        if decl.impl is not None:
            if decl.code:
                self.error(decl.impl_span, "an actor type has either inline C blocks or an 'impl' file, not both")
            base = FsPath(self.actor_type_files[decl.name]) if decl.name in self.actor_type_files else FsPath(".")
            impl_path = _module_dir(base) / decl.impl
            if not impl_path.is_file():
                self.error(decl.impl_span, f"implementation file '{decl.impl}' not found (looked at {impl_path})")
        elif "step" not in kinds:
            self.error(decl.name_span, f"actor type '{decl.name}' has no 'step' block and no 'impl' file",
                       "add step {{ ... }} with the C code of one firing")
        if not any(p.direction == "out" for p in decl.ports):
            self.error(decl.name_span, f"actor type '{decl.name}' has no output port")

    # ================================================================ devices

    def check_device_type(self, decl: ast.DeviceType) -> None:
        names: dict[str, Span] = {}
        for item in (*decl.params, *decl.ports, *decl.exports, *decl.parts):
            if item.name in names:
                self.error(item.name_span, f"'{item.name}' is declared twice in device type '{decl.name}'",
                           notes=[note(names[item.name], "first declared here")])
            names[item.name] = item.name_span
        for p in decl.params:
            self.resolve_type(p.type, allow_string=True)
        if decl.driver is not None and decl.parts:
            self.error(decl.driver_span, "a device type with a driver is primitive and cannot have parts",
                       "move the driver into a device type of its own and make it a part")
        if decl.driver is None and (decl.ports or decl.claims):
            what = "data ports" if decl.ports else "claims"
            self.error(decl.name_span, f"device type '{decl.name}' has {what} but no driver",
                       "add driver \"name\", or re-export a part's data with out x = part.y")
        if decl.driver is not None and not re.fullmatch(r"[a-z_][a-z0-9_]*", decl.driver):
            self.error(decl.driver_span, f"driver name '{decl.driver}' must be a C identifier in lower case")
        if not decl.parts and decl.exports:
            self.error(decl.exports[0].span, "a re-export needs a part to take its data from")

    def elaborate_device(self, decl: ast.DeviceInstance) -> None:
        """Flatten a device instance into primitive devices and data paths."""
        dtype = self.lookup(decl.type_name, decl.type_span, (ast.DeviceType,), "device type")
        if dtype is None:
            return
        self.top_devices[decl.name] = decl
        args = self.device_args(dtype, decl.args, decl.span, self.const_typer())
        if args is not None:
            self._elaborate(decl.name, dtype, args, decl.span, ())

    def device_args(self, dtype: ast.DeviceType, actuals, span: Span, typer: ExprTyper):
        values: dict[str, object] = {}
        misspelt: set[str | None] = set()
        formals = {p.name: p for p in dtype.params}
        ok = True
        for a in actuals:
            formal = formals.get(a.name)
            if formal is None:
                self.error(a.name_span, f"device type '{dtype.name}' has no parameter '{a.name}'",
                           did_you_mean(a.name, formals))
                misspelt.add(closest(a.name, formals))  # not reported as missing as well
                ok = False
                continue
            if a.name in values:
                self.error(a.name_span, f"parameter '{a.name}' is given twice")
                continue
            t = self.resolve_type(formal.type, allow_string=True)
            if t is None:
                values[a.name] = None
                ok = False
                continue
            v = typer.expect_const(a.value, t, f"device parameter '{a.name}'")
            if v.type is None:
                ok = False
            choices = self.choice_values(formal, t) if v.type is not None else None
            if choices is not None and v.const not in choices:
                self.error(a.value.span, f"device parameter '{a.name}' must be one of "
                                         f"{', '.join(_show(c, t) for c in choices)}")
                ok = False
            values[a.name] = v.const
        for name, formal in formals.items():
            if name not in values:
                if formal.default is not None:
                    t = self.resolve_type(formal.type, allow_string=True)
                    v = self.const_typer().expect_const(formal.default, t, f"the default of '{name}'") if t else ERROR
                    values[name] = v.const
                    ok = ok and v.type is not None
                elif name not in misspelt:
                    self.error(span, f"device type '{dtype.name}' needs parameter '{name}'")
                    ok = False
        return values if ok else None

    def choice_values(self, formal: ast.FormalParam, t: T.ValueType) -> list | None:
        """The constants a parameter declared ``in (...)`` may take, or None
        (no choices, or a choice in error, reported)."""
        if formal.choices is None:
            return None
        values = [self.const_typer().expect_const(c, t, "a choice") for c in formal.choices]
        return None if any(v.type is None for v in values) else [v.const for v in values]

    def _device_typer(self, dtype: ast.DeviceType, args: dict) -> ExprTyper:
        def resolve(path: ast.Path):
            if path.parts[0] in args and len(path.parts) == 1:
                formal = next(p for p in dtype.params if p.name == path.parts[0])
                t = T.ALL_TYPES.get(formal.type.name, T.INT32)
                return Symbol("formal", t, args[path.parts[0]], None, path.parts[0])
            return self.global_symbol(path, allow=("const",))
        return self.typer(resolve, runtime=False)

    def _elaborate(self, path: str, dtype: ast.DeviceType, args: dict, span: Span, outer: tuple) -> bool:
        """``span`` is the instance or part in the model's own files that
        stands for this device; ``outer`` the device types around it. False
        when a part could not be elaborated (its error is reported)."""
        typer = self._device_typer(dtype, args)
        if dtype.driver is not None:
            ports = {}
            for p in dtype.ports:
                t = self.resolve_type(p.type)
                if t is None:
                    continue
                rate = self.eval_rate(p.rate, typer) if p.rate is not None else 1
                ports[p.name] = DevicePort(p.name, p.direction, t, rate or 1)
            claims = []
            for r in dtype.claims:
                claim = self.eval_claim(r, typer, path)
                if claim is not None:
                    claim.span = span  # the device's declaration, not the device type's claim
                    claims.append(claim)
                    self.claims.append(claim)
            device = PrimitiveDevice(path, dtype, dtype.driver, args, ports, claims, span)
            self.devices.append(device)
            for port in ports.values():
                self.device_data.setdefault(f"{path}.{port.name}", DeviceDatum(device, port, f"{path}.{port.name}"))
            return len(ports) == len(dtype.ports)
        complete = True  # every part elaborated: its data can be re-exported
        for part in dtype.parts:
            ptype = self.lookup(part.type_name, part.type_span, (ast.DeviceType,), "device type")
            complete = complete and ptype is not None
            if ptype is None:
                continue
            if ptype is dtype or ptype in outer:
                cycle = [t.name for t in (*outer, dtype)][[*outer, dtype].index(ptype):] + [ptype.name]
                self.error(part.type_span, f"device type '{ptype.name}' contains itself"
                                           + (f" ({' -> '.join(cycle)})" if len(cycle) > 2 else ""))
                complete = False
                continue
            part_args = self.device_args(ptype, part.args, part.span, typer)
            complete = complete and part_args is not None
            if part_args is not None:
                part_span = span if _in_library(part.span) else part.span
                complete = self._elaborate(f"{path}.{part.name}", ptype, part_args, part_span,
                                           (*outer, dtype)) and complete
        for export in dtype.exports if complete else ():
            target = self.device_data.get(f"{path}.{export.target.text}")
            if target is None:
                self.error(export.target.span, f"'{export.target.text}' is not a data port of a part of "
                                               f"device type '{dtype.name}'")
                complete = False
                continue
            if target.port.direction != export.direction:
                self.error(export.span, f"'{export.name}' is declared '{export.direction}' but "
                                        f"'{export.target.text}' is '{target.port.direction}'")
                complete = False
                continue
            alias = f"{path}.{export.name}"
            self.device_data[alias] = target
            if target.name == f"{path}.{export.target.text}":
                target.name = alias  # the shortest name the model gives it
        return complete

    def eval_claim(self, r: ast.Resource, typer: ExprTyper, owner: str) -> Claim | None:
        if r.index is None:
            m = re.fullmatch(r"([A-Za-z_]+?)(\d+)", r.kind)
            if m is None:
                self.error(r.span, f"resource '{r.kind}' needs an index, as in {r.kind}[0]")
                return None
            return Claim(m.group(1), int(m.group(2)), r.span, owner)
        v = typer.expect_const(r.index, None, "a resource index")
        if v.type is None:
            return None
        if not (v.type is T.STRING or (v.type.is_integer and v.type is not T.TIME and v.const >= 0)):
            self.error(r.index.span, "a resource index is a non-negative integer or a pin name string")
            return None
        return Claim(r.kind, v.const, r.span, owner)

    def eval_rate(self, e: ast.Expr, typer: ExprTyper) -> int | None:
        v = typer.expect_const(e, None, "a rate")
        if v.type is None:
            return None
        if not (v.type.is_integer and v.type is not T.TIME) or not 1 <= v.const <= _MAX_RATE:
            self.error(e.span, f"a rate is a whole number of tokens from 1 to {_MAX_RATE}, not {v.const}")
            return None
        return v.const

    def device_datum(self, path: ast.Path):
        """The device datum a path names, or (message, hint)."""
        datum = self.device_data.get(path.text)
        if datum is not None:
            return datum
        head = path.parts[0]
        if head not in self.top_devices:
            return (f"unknown device '{head}'", None)
        prefix = ""
        for i, part in enumerate(path.parts):
            prefix = f"{prefix}.{part}" if prefix else part
            if i and not any(p.path == prefix or p.path.startswith(prefix + ".") for p in self.devices):
                options = sorted({k[len(prefix) - len(part):].split(".")[0] for k in self.device_data
                                  if k.startswith(prefix[:-len(part)])})
                return (f"device '{prefix[:-len(part) - 1]}' has no part or datum '{part}'",
                        did_you_mean(part, options))
        options = sorted(k[len(path.text) + 1:] for k in self.device_data if k.startswith(path.text + "."))
        single = {id(self.device_data[f"{path.text}.{o}"]) for o in options}
        if len(single) == 1:  # a device with one datum stands for it (docs/language.md)
            return self.device_data[f"{path.text}.{options[0]}"]
        if options:
            return (f"'{path.text}' is a device, not a datum", f"name one of its data: {', '.join(options[:6])}")
        return (f"'{path.text}' does not name device data", None)

    # ================================================================ dataflows

    def check_dataflow(self, decl: ast.Dataflow) -> None:
        info = DataflowInfo(decl, {}, [])
        self.dataflows[decl.name] = info
        pending = []
        for inst in decl.instances:
            if inst.name in info.instances or any(p[0].name == inst.name for p in pending):
                self.error(inst.name_span, f"actor instance '{inst.name}' is declared twice in dataflow '{decl.name}'")
                continue
            atype = self.lookup(inst.type_name, inst.type_span, (ast.ActorType,), "actor type")
            if atype is not None:
                pending.append((inst, atype))
        # Bind type parameters: explicit ones first, then inference from edges.
        bindings = {inst.name: self.explicit_type_args(inst, atype) for inst, atype in pending}
        self.infer_type_args(decl, pending, bindings)
        for inst, atype in pending:
            b = bindings[inst.name]
            if b is None:
                continue
            instance = self.instantiate(inst, atype, b)
            if instance is not None:
                instance.dataflow = info
                info.instances[inst.name] = instance
        connected: dict[tuple[str, str], Span] = {}
        sinks: dict[str, Span] = {}
        for edge in decl.edges:
            src = self.endpoint(edge.src, info, "source")
            dst = self.endpoint(edge.dst, info, "destination")
            if src is None or dst is None:
                continue
            if src.kind == "actor" and src.target.actor_type and _port(src.target.actor_type, src.port).direction != "out":
                self.error(edge.src.span, f"'{edge.src.text}' is an input port; an edge starts at an output")
                continue
            if dst.kind == "actor" and _port(dst.target.actor_type, dst.port).direction != "in":
                self.error(edge.dst.span, f"'{edge.dst.text}' is an output port; an edge ends at an input")
                continue
            if src.kind == "channel" and dst.kind == "channel":
                self.error(edge.span, "an edge cannot join two channels")
                continue
            if not T.widens(src.type, dst.type):
                hint = (f"convert with Cast<{src.type}, {dst.type}>()"
                        if src.type.is_numeric and dst.type.is_numeric else None)
                self.error(edge.span, f"type mismatch: '{edge.src.text}' is '{src.type}' but "
                                      f"'{edge.dst.text}' is '{dst.type}'", hint)
                continue
            if dst.kind == "actor":
                key = (dst.target.name, dst.port)
                if key in connected:
                    self.error(edge.dst.span, f"input '{edge.dst.text}' already has an edge",
                               "an input port takes exactly one edge; merge the sources with an actor",
                               [note(connected[key], "the other edge")])
                    continue
                connected[key] = edge.span
            elif dst.kind in ("var", "device"):
                if dst.label in sinks:
                    self.error(edge.dst.span, f"'{edge.dst.text}' is written twice in dataflow '{decl.name}'",
                               notes=[note(sinks[dst.label], "the other edge")])
                    continue
                sinks[dst.label] = edge.span
            tokens = self.delay_tokens(edge.delay, dst.type) if edge.delay is not None else ()
            if tokens and (src.kind not in ("actor",) and dst.kind not in ("actor",)):
                self.error(edge.delay.span, "initial tokens belong on edges between actors")
            e = EdgeInfo(edge, src, dst, tokens)
            info.edges.append(e)
            if dst.kind in ("var", "device"):
                dst.target.writers.append(Writer(info, edge.span))
            if dst.kind == "channel":
                dst.target.producers.append(e)
            if src.kind == "channel":
                src.target.consumers.append(e)
        for name, instance in info.instances.items():
            for port in instance.actor_type.ports:
                if port.direction == "in" and (name, port.name) not in connected:
                    self.error(instance.decl.name_span, f"input '{name}.{port.name}' is not connected",
                               f"add an edge such as: something -> {name}.{port.name}")

    def explicit_type_args(self, inst: ast.Instance, atype: ast.ActorType) -> dict | None:
        if not inst.type_args:
            return {}
        if len(inst.type_args) != len(atype.type_params):
            self.error(inst.type_span, f"actor type '{atype.name}' takes {len(atype.type_params)} type "
                                       f"argument(s), {len(inst.type_args)} given")
            return None
        bound = {}
        for tp, ref in zip(atype.type_params, inst.type_args):
            t = self.resolve_type(ref)
            if t is None:
                return None
            if not T.satisfies_bound(t, tp.bound):
                self.error(ref.span, f"'{t}' is not {_a(tp.bound)} type, as '{atype.name}' requires of {tp.name}",
                           f"{tp.name} must be {T.BOUNDS[tp.bound]}")
                return None
            bound[tp.name] = t
        return bound

    def infer_type_args(self, decl: ast.Dataflow, pending, bindings) -> None:
        """Bind missing type parameters to the narrowest type that every
        connected type widens to (docs/language.md, 'type arguments')."""
        by_name = {inst.name: (inst, atype) for inst, atype in pending}
        open_insts = [inst.name for inst, atype in pending
                      if bindings[inst.name] is not None and len(bindings[inst.name]) < len(atype.type_params)]
        for _ in range(len(open_insts) + 1):
            progress = False
            for name in open_insts:
                inst, atype = by_name[name]
                b = bindings[name]
                if b is None or len(b) == len(atype.type_params):
                    continue
                for tp in atype.type_params:
                    if tp.name in b:
                        continue
                    lower, upper = self._connected_types(decl, name, atype, tp.name, by_name, bindings)
                    if lower is None:
                        continue  # a neighbour is still unbound
                    chosen = T.join(lower) if lower else (T.join(upper) if len(set(upper)) == 1 else None)
                    if chosen is None and not lower and len(upper) > 1:
                        chosen = next((u for u in upper if all(T.widens(u, o) for o in upper)), None)
                    if chosen is not None and T.satisfies_bound(chosen, tp.bound):
                        b[tp.name] = chosen
                        progress = True
            if not progress:
                break
        for name in open_insts:
            inst, atype = by_name[name]
            b = bindings[name]
            if b is None:
                continue
            missing = [tp.name for tp in atype.type_params if tp.name not in b]
            if missing:
                example = ", ".join("int16" for _ in atype.type_params)
                self.error(inst.type_span, f"cannot infer type argument {', '.join(missing)} of '{atype.name}' "
                                           f"from what '{name}' is connected to",
                           f"give it explicitly: {name} = {atype.name}<{example}>(...)")
                bindings[name] = None

    def _connected_types(self, decl, name, atype, tparam, by_name, bindings):
        lower, upper = [], []
        t_ports = {p.name: p.direction for p in atype.ports if p.type.name == tparam}
        for edge in decl.edges:
            for mine, other, kind in ((edge.dst, edge.src, "lower"), (edge.src, edge.dst, "upper")):
                if mine.parts[0] != name or len(mine.parts) != 2 or mine.parts[1] not in t_ports:
                    continue
                t = self._peek_type(other, decl, by_name, bindings)
                if t == "unbound":
                    return None, None
                if t is not None:
                    (lower if kind == "lower" else upper).append(t)
        return lower, upper

    def _peek_type(self, path: ast.Path, decl, by_name, bindings):
        """The type at the far end of an edge, without reporting errors."""
        if path.parts[0] in by_name and len(path.parts) == 2:
            inst, atype = by_name[path.parts[0]]
            port = next((p for p in atype.ports if p.name == path.parts[1]), None)
            if port is None:
                return None
            if port.type.name in {tp.name for tp in atype.type_params}:
                b = bindings.get(inst.name)
                if b is None:
                    return None
                return b.get(port.type.name, "unbound")
            return T.SCALARS.get(port.type.name)
        head = self.globals.get(path.parts[0])
        if isinstance(head, ast.Data) and head.name in self.data:
            return self.data[head.name].type
        if isinstance(head, ast.Channel) and head.name in self.channels:
            return self.channels[head.name].type
        datum = self.device_data.get(path.text)
        return datum.type if datum else None

    def instantiate(self, inst: ast.Instance, atype: ast.ActorType, bindings: dict) -> ActorInstanceInfo | None:
        def bind(ref: ast.TypeRef):
            return bindings.get(ref.name) or T.ALL_TYPES.get(ref.name)

        formals = {p.name: p for p in atype.params}
        sizing = _sizing_params(atype)
        args: dict[str, ArgValue] = {}
        given: set[str] = set()
        misspelt: set[str | None] = set()
        ok = True
        for a in inst.args:
            formal = formals.get(a.name)
            if formal is None:
                self.error(a.name_span, f"actor type '{atype.name}' has no parameter '{a.name}'",
                           did_you_mean(a.name, formals))
                misspelt.add(closest(a.name, formals))  # not reported as missing as well
                ok = False
                continue
            if a.name in given:
                self.error(a.name_span, f"parameter '{a.name}' is given twice")
                continue
            given.add(a.name)
            t = bind(formal.type)
            if t is None:
                ok = False
                continue
            used: list = []
            typer = self.typer(lambda p: self.global_symbol(p, allow=("const", "param")), used=used)
            what = f"parameter '{a.name}' of '{inst.name}'"
            v = typer.expect_const(a.value, t, what) if (a.name in sizing or t is T.STRING) else typer.expect(a.value, t, what)
            if v.type is None:
                ok = False
                continue
            choices = self.choice_values(formal, t) if v.is_const else None
            if choices is not None and v.const not in choices:
                self.error(a.value.span, f"{what} must be one of {', '.join(_show(c, t) for c in choices)}")
                ok = False
                continue
            params = tuple(sorted({sym.name for _, sym in used if sym.kind == "param"}))
            args[a.name] = ArgValue(t, v.const, None if v.is_const else a.value, params,
                                    None if v.is_const else v.node)
        for name, formal in formals.items():
            if name in given or name in misspelt:
                continue
            if formal.default is None:
                self.error(inst.type_span, f"'{inst.name}' needs parameter '{name}' of actor type '{atype.name}'",
                           f"write {atype.name}({name} = ...)")
                ok = False
                continue
            t = bind(formal.type)
            v = self.const_typer().expect_const(formal.default, t, f"the default of '{name}'") if t else ERROR
            if v.type is None:
                ok = False
                continue
            args[name] = ArgValue(t, v.const, None)
        if not ok:
            return None
        consts = {n: a.const for n, a in args.items() if a.const is not None}

        def resolve(path: ast.Path):
            if len(path.parts) == 1 and path.parts[0] in consts:
                return Symbol("formal", args[path.parts[0]].type, consts[path.parts[0]], None, path.parts[0])
            if len(path.parts) == 1 and path.parts[0] in formals:
                return (f"'{path.parts[0]}' sizes something, so '{inst.name}' must give it a compile-time constant",
                        None)
            return self.global_symbol(path, allow=("const",))

        typer = self.typer(resolve, runtime=False)
        port_types, port_rates, state_types = {}, {}, {}
        for port in atype.ports:
            port_types[port.name] = bind(port.type)
            if port_types[port.name] is None:
                return None  # an unknown type, reported with the actor type
            rate = self.eval_rate(port.rate, typer) if port.rate is not None else 1
            if rate is None:
                return None
            port_rates[port.name] = rate
        for st in atype.states:
            size = None
            if st.type.size is not None:
                v = typer.expect_const(st.type.size, None, "an array size")
                if v.type is None:
                    return None
                if not (v.type.is_integer and v.type is not T.TIME) or not 1 <= v.const <= 65535:
                    self.error(st.type.span, f"array size of state '{st.name}' must be 1..65535, not {v.const} "
                                             f"(in '{inst.name}')")
                    return None
                size = v.const
            if bind(st.type) is None:
                return None  # an unknown type, reported with the actor type
            state_types[st.name] = (bind(st.type), size)
        return ActorInstanceInfo(inst, atype, dict(bindings), args, port_types, port_rates, state_types)

    def endpoint(self, path: ast.Path, info: DataflowInfo, side: str) -> Endpoint | None:
        head = path.parts[0]
        if head in info.instances or any(i.name == head for i in info.decl.instances):
            instance = info.instances.get(head)
            if instance is None:
                return None  # its declaration failed; reported there
            if len(path.parts) != 2:
                self.error(path.span, f"'{path.text}': name a port of actor '{head}' as {head}.port")
                return None
            port = path.parts[1]
            if port not in instance.port_types:
                names = [p.name for p in instance.actor_type.ports]
                self.error(path.part_spans[1], f"actor '{head}' ({instance.actor_type.name}) has no port '{port}'",
                           did_you_mean(port, names) or f"its ports: {', '.join(names)}")
                return None
            return Endpoint("actor", instance, port, instance.port_types[port], instance.port_rates[port], path)
        decl = self.globals.get(head)
        if decl is None:
            candidates = [i.name for i in info.decl.instances] + [
                n for n, d in self.globals.items() if isinstance(d, (ast.Data, ast.Channel, ast.DeviceInstance))]
            self.error(path.part_spans[0], f"unknown name '{head}' in dataflow '{info.name}'",
                       did_you_mean(head, candidates))
            return None
        if isinstance(decl, ast.Data):
            data = self.data.get(head)
            if data is None or len(path.parts) > 1:
                if len(path.parts) > 1:
                    self.error(path.span, f"'{head}' is a {decl.kind} and has no member '{path.parts[1]}'")
                return None
            if side == "destination" and decl.kind == "param":
                self.error(path.span, f"param '{head}' cannot be written by a dataflow",
                           "params are written only through the debug and service interfaces; use a var")
                return None
            return Endpoint(decl.kind, data, None, data.type, 1, path)
        if isinstance(decl, ast.Channel):
            ch = self.channels.get(head)
            if ch is None:
                return None
            return Endpoint("channel", ch, None, ch.type, None, path)
        if isinstance(decl, ast.DeviceInstance):
            datum = self.device_datum(path)
            if isinstance(datum, tuple):
                self.error(path.span, datum[0], datum[1])
                return None
            want = "out" if side == "source" else "in"
            if datum.port.direction != want:
                what = "an output (device -> application)" if datum.port.direction == "out" else \
                    "an input (application -> device)"
                self.error(path.span, f"'{path.text}' is {what} and cannot be an edge's {side}")
                return None
            return Endpoint("device", datum, None, datum.type, datum.port.rate, path)
        self.error(path.part_spans[0], f"'{head}' is {_a(kind_name(decl))}; an edge joins actor ports, vars, "
                                       "params, channels and device data")
        return None

    # ================================================================ charts

    def check_chart(self, decl: ast.Chart) -> None:
        steps: dict[str, StepInfo] = {}
        for s in decl.steps:
            if s.name in steps:
                self.error(s.name_span, f"step '{s.name}' is declared twice in chart '{decl.name}'",
                           notes=[note(steps[s.name].decl.name_span, "first declared here")])
                continue
            runs = []
            for r in s.runs:
                df = self.lookup(r.name, r.name_span, (ast.Dataflow,), "dataflow")
                if df is not None and df.name in self.dataflows:
                    runs.append(self.dataflows[df.name])
            steps[s.name] = StepInfo(s, len(steps), (), runs)
        info = ChartInfo(decl, steps, [], None)
        self.charts[decl.name] = info
        initials = [s for s in steps.values() if s.decl.initial]
        if not initials:
            self.error(decl.name_span, f"chart '{decl.name}' has no initial step",
                       "mark the step it starts in: initial step Name { ... }")
        for extra in initials[1:]:
            self.error(extra.decl.span, f"chart '{decl.name}' has more than one initial step",
                       notes=[note(initials[0].decl.span, "the first initial step")])
        info.initial = initials[0] if initials else None
        for idx, t in enumerate(decl.transitions):
            srcs = [self._step_ref(steps, r, decl) for r in t.sources]
            dsts = [self._step_ref(steps, r, decl) for r in t.targets]
            if None in srcs or None in dsts:
                continue
            for group in (t.sources, t.targets):
                names = [r.name for r in group]
                for r in group:
                    if names.count(r.name) > 1:
                        self.error(r.span, f"step '{r.name}' appears twice in one transition")
                        break
            info.transitions.append(TransitionInfo(t, idx, srcs, dsts))
        for s in steps.values():
            for action in s.decl.entry:
                s.entry_actions.extend(self.check_assignment(action, info))
            for action in s.decl.exit:
                s.exit_actions.extend(self.check_assignment(action, info))
        for tr in info.transitions:
            v = self.typer(lambda p: self.chart_symbol(p, info)).check(tr.decl.guard)
            tr.guard = v.node
            if v.type is not None and v.type is not T.BOOL:
                self.error(tr.decl.guard.span, f"a transition guard must be a bool, not '{v.type}'",
                           "compare it, e.g. x > 0")
        if info.initial is not None:
            self.check_chart_structure(info)

    def _step_ref(self, steps, ref: ast.StepRef, decl: ast.Chart):
        s = steps.get(ref.name)
        if s is None:
            self.error(ref.span, f"chart '{decl.name}' has no step '{ref.name}'", did_you_mean(ref.name, steps))
        return s

    def chart_symbol(self, path: ast.Path, chart: ChartInfo):
        if path.parts[0] in chart.steps and path.parts[0] not in self.globals:
            if len(path.parts) != 2 or path.parts[1] not in ("time", "active"):
                return (f"a step offers '{path.parts[0]}.time' and '{path.parts[0]}.active'", None)
            kind = "step_" + path.parts[1]
            return Symbol(kind, T.TIME if path.parts[1] == "time" else T.BOOL, None, chart.steps[path.parts[0]],
                          path.text)
        symbol = self.global_symbol(path)
        if isinstance(symbol, tuple) and path.parts[0] not in self.globals and len(path.parts) > 1:
            # `Idel.time`: a misspelt step rather than a misspelt global
            return symbol[0], did_you_mean(path.parts[0], chart.steps) or symbol[1]
        return symbol

    def check_assignment(self, action: ast.Assign, chart: ChartInfo) -> list[ActionInfo]:
        target = action.target
        head = self.globals.get(target.parts[0])
        if isinstance(head, ast.Data) and len(target.parts) == 1:
            if head.kind == "param":
                self.error(target.span, f"param '{head.name}' cannot be assigned by a chart",
                           "params are written only through the debug and service interfaces; use a var")
                return []
            data = self.data.get(head.name)
            if data is None:
                return []
            t, writers = data.type, data.writers
        elif isinstance(head, ast.DeviceInstance):
            datum = self.device_datum(target)
            if isinstance(datum, tuple):
                self.error(target.span, *datum)
                return []
            if datum.port.direction != "in":
                self.error(target.span, f"'{target.text}' is a device output; only device inputs can be assigned")
                return []
            t, writers = datum.type, datum.writers
        else:
            what = _a(kind_name(head)) if head is not None else "not declared"
            hint = None if head is not None else did_you_mean(target.parts[0], [
                n for n, d in self.globals.items() if isinstance(d, ast.Data) and d.kind == "var"])
            self.error(target.span, f"cannot assign to '{target.text}': it is {what}; "
                                    "an action assigns a var or a device input", hint)
            return []
        v = self.typer(lambda p: self.chart_symbol(p, chart)).expect(action.value, t,
                                                                    f"the value assigned to '{target.text}'")
        writers.append(Writer(chart, action.span))
        if v.type is None:
            return []
        return [ActionInfo(action, datum if isinstance(head, ast.DeviceInstance) else data, v.node)]

    def check_chart_structure(self, chart: ChartInfo) -> None:
        """Reachability and parallel branches (docs/language.md, 'charts').

        Every step gets the branch it runs in: the initial step the root
        branch (); a divergence ``S -> (A, B)`` puts A and B in branches
        (t, 0) and (t, 1) below S's; a convergence must join exactly the
        branches of one divergence and leads back to the branch above them.
        """
        branch: dict[str, tuple] = {chart.initial.name: ()}
        where: dict[str, Span] = {chart.initial.name: chart.initial.decl.name_span}
        divergences: dict[int, int] = {}
        changed = True
        reported: set[int] = set()
        rounds = 0
        while changed and rounds <= len(chart.transitions) + 1:
            changed = False
            rounds += 1
            for tr in chart.transitions:
                if tr.index in reported or any(s.name not in branch for s in tr.sources):
                    continue
                src_branches = [branch[s.name] for s in tr.sources]
                if len(tr.sources) == 1:
                    base = src_branches[0]
                else:
                    base = self._convergence_base(tr, src_branches, divergences)
                    if base is None:
                        reported.add(tr.index)
                        continue
                if len(tr.targets) == 1:
                    targets = {tr.targets[0].name: base}
                else:
                    divergences[tr.index] = len(tr.targets)
                    targets = {t.name: base + ((tr.index, i),) for i, t in enumerate(tr.targets)}
                for name, b in targets.items():
                    if name not in branch:
                        branch[name] = b
                        where[name] = tr.decl.span
                        changed = True
                    elif branch[name] != b:
                        reported.add(tr.index)
                        self.error(tr.decl.span, f"step '{name}' is entered from two different parallel branches",
                                   "a step belongs to one branch; join branches with a convergence (A, B) -> C",
                                   [note(where[name], f"'{name}' is entered here too")])
        for s in chart.steps.values():
            if s.name not in branch:
                self.error(s.decl.name_span, f"step '{s.name}' is unreachable from the initial step "
                                             f"'{chart.initial.name}'")
            else:
                s.branch = branch[s.name]

    def _convergence_base(self, tr: TransitionInfo, src_branches, divergences):
        tails = {b[-1] if b else None for b in src_branches}
        bases = {b[:-1] for b in src_branches}
        divs = {t[0] for t in tails if t is not None}
        ok = None not in tails and len(bases) == 1 and len(divs) == 1
        if ok:
            div = divs.pop()
            indices = sorted(t[1] for t in tails)
            ok = indices == list(range(divergences.get(div, -1)))
        if not ok:
            self.error(tr.decl.span, "a convergence must join one step of every branch of a single divergence",
                       "join exactly the branches that one 'A -> (B, C)' transition started")
            return None
        return bases.pop()

    # ================================================================ tasks

    def check_task(self, decl: ast.Task) -> None:
        attrs: dict[str, object] = {}
        typer = self.const_typer()
        for a in decl.attrs:
            if a.key in attrs:
                self.error(a.span, f"'{a.key}' is given twice for task '{decl.name}'")
                continue
            v = typer.expect_const(a.value, T.TIME, f"the {a.key} of task '{decl.name}'")
            attrs[a.key] = (v.const, a.span) if v.type is not None else None
        if "period" not in attrs:
            self.error(decl.name_span, f"task '{decl.name}' has no period", "write: task name period 10 ms { ... }")
            return
        if any(v is None for v in attrs.values()):
            return
        period, pspan = attrs["period"]
        offset, ospan = attrs.get("offset", (Fraction(0), None))
        deadline, dspan = attrs.get("deadline", (period, None))
        wcet, wspan = attrs.get("wcet", (None, None))
        bad = False
        if period <= 0:
            self.error(pspan, "a task's period must be positive")
            bad = True
        elif not _whole_us(period):
            self.error(pspan, "a task's period is a whole number of microseconds")
            bad = True
        if not bad and not 0 <= offset < period:
            self.error(ospan, f"the offset must be below the period ({_show(period, T.TIME)})")
            bad = True
        if not bad and not 0 < deadline <= period:
            self.error(dspan, f"the deadline must be positive and at most the period ({_show(period, T.TIME)})")
            bad = True
        if not bad and wcet is not None and not 0 < wcet <= deadline:
            self.error(wspan, f"the wcet must be positive and at most the deadline ({_show(deadline, T.TIME)})")
            bad = True
        runs = []
        for r in decl.runs:
            target = self.lookup(r.name, r.name_span, (ast.Dataflow, ast.Chart), "dataflow or chart")
            if target is None:
                continue
            runs.append(self.dataflows.get(r.name) or self.charts.get(r.name))
        if bad:
            return
        info = TaskInfo(decl, period, offset, deadline, wcet, [r for r in runs if r is not None])
        self.tasks[decl.name] = info

    def check_run_once(self) -> None:
        """Nothing is run by two tasks (directly or through a chart)."""
        owner: dict[str, tuple[TaskInfo, Span]] = {}

        def claim(item, task: TaskInfo, span: Span) -> None:
            first = owner.get(item.name)
            if first is not None and first[0] is not task:
                self.error(span, f"{'chart' if isinstance(item, ChartInfo) else 'dataflow'} '{item.name}' is run "
                                 f"by task '{first[0].name}' and by task '{task.name}'",
                           "a dataflow or chart runs in one task; split it, or use a channel between tasks",
                           [note(first[1], f"run by task '{first[0].name}' here")])
                return
            owner.setdefault(item.name, (task, span))
            item.task = task

        for task in self.tasks.values():
            for r, run in zip(task.runs, [r for r in task.decl.runs if r.name in self.dataflows or r.name in self.charts]):
                claim(r, task, run.span)
                if isinstance(r, ChartInfo):
                    for step in r.steps.values():
                        for df, run_decl in zip(step.runs, step.decl.runs):
                            claim(df, task, run_decl.span)

    def check_writers(self) -> None:
        """One writer per var and device input: all writes come from one task."""
        targets = [(f"var '{d.name}'", d) for d in self.data.values() if d.kind == "var"]
        seen: set[int] = set()
        for name, datum in self.device_data.items():
            if datum.port.direction == "in" and id(datum) not in seen:
                seen.add(id(datum))
                targets.append((f"device input '{datum.name}'", datum))
        for label, target in targets:
            first = None
            for w in target.writers:
                task = w.owner.task
                if task is None:
                    continue
                if first is None:
                    first = (task, w)
                elif first[0] is not task:
                    self.error(w.span, f"{label} is written by task '{task.name}' and by task '{first[0].name}'",
                               "each var and device input has one writing task; pass data between tasks "
                               "through a channel",
                               [note(first[1].span, f"written in task '{first[0].name}' here")])
                    break

    def check_channels_connected(self) -> None:
        for ch in self.channels.values():
            if not ch.producers:
                self.error(ch.decl.name_span, f"channel '{ch.name}' has no producer",
                           f"write to it from a dataflow: x.y -> {ch.name}")
            if not ch.consumers:
                self.error(ch.decl.name_span, f"channel '{ch.name}' has no consumer",
                           f"read it in a dataflow: {ch.name} -> x.in")
            for group, role in ((ch.producers, "produced"), (ch.consumers, "consumed")):
                for extra in group[1:]:
                    self.error(extra.decl.span, f"channel '{ch.name}' is {role} by more than one edge",
                               notes=[note(group[0].decl.span, "the first edge")])

    # ================================================================ interfaces and resources

    _INTERFACE_KEYS = {
        "debug": {"baud"},
        "modbus-rtu": {"baud", "parity", "unit"},
        "modbus-tcp": {"port", "unit"},
    }
    _DEFAULTS = {
        "debug": {"baud": 115200},
        "modbus-rtu": {"baud": 19200, "parity": "even", "unit": 1},
        "modbus-tcp": {"port": 502, "unit": 1},
    }

    def check_interface(self, iface: ast.Interface) -> None:
        kind = "debug" if iface.kind == "debug" else f"modbus-{iface.mode}"
        for other in self.interfaces:
            if other.kind == kind:
                self.error(iface.span, f"a model has at most one {kind.replace('-', ' ')} interface",
                           notes=[note(other.decl.span, "the other one")])
                return
        settings = dict(self._DEFAULTS[kind])
        given: set[str] = set()
        for a in iface.attrs:
            if a.key not in self._INTERFACE_KEYS[kind]:
                self.error(a.span, f"'{a.key}' is not a setting of the {kind.replace('-', ' ')} interface",
                           f"its settings: {', '.join(sorted(self._INTERFACE_KEYS[kind]))}")
                continue
            if a.key in given:
                self.error(a.span, f"'{a.key}' is given twice")
                continue
            given.add(a.key)
            value = a.value
            if a.key == "parity":
                if value not in ("none", "even", "odd"):
                    self.error(a.value_span, f"parity must be none, even or odd, not '{value}'")
                    continue
            elif not isinstance(value, int):
                self.error(a.value_span, f"'{a.key}' takes a number, not '{value}'")
                continue
            elif a.key == "baud" and not 300 <= value <= 4_000_000:
                self.error(a.value_span, f"baud rate {value} is outside 300..4000000")
                continue
            elif a.key == "unit" and not 1 <= value <= 247:
                self.error(a.value_span, f"Modbus unit id {value} is outside 1..247")
                continue
            elif a.key == "port" and not 1 <= value <= 65535:
                self.error(a.value_span, f"TCP port {value} is outside 1..65535")
                continue
            settings[a.key] = value
        claim = None
        if kind == "modbus-tcp":
            if iface.resource is not None:
                self.error(iface.resource.span, "Modbus TCP runs on the board's network, not 'on' a resource")
        elif iface.resource is None:
            self.error(iface.span, f"the {kind.replace('-', ' ')} interface needs a UART: 'on uart0'")
            return
        else:
            claim = self.eval_claim(iface.resource, self.const_typer(), kind.replace("-", " "))
            if claim is not None:
                if claim.kind != "uart":
                    self.error(iface.resource.span, f"the {kind.replace('-', ' ')} interface runs on a UART, "
                                                    f"not on '{claim}'")
                    return
                self.claims.append(claim)
        self.interfaces.append(InterfaceInfo(iface, kind, claim, settings))

    def check_claims(self) -> None:
        first: dict[tuple, Claim] = {}
        for c in self.claims:
            other = first.get(c.key)
            if other is None:
                first[c.key] = c
                continue
            self.error(c.span, f"resource {c} is claimed by {_owner(c)} and by {_owner(other)}",
                       "each resource has one owner; choose another pin, channel or UART",
                       [note(other.span, f"claimed by {_owner(other)} here")])


# ==================================================================== helpers


def _owner(c: Claim) -> str:
    return f"interface '{c.owner}'" if " " in c.owner or c.owner == "debug" else f"device '{c.owner}'"


def _port(atype: ast.ActorType, name: str) -> ast.ActorPort:
    return next(p for p in atype.ports if p.name == name)


def _sizing_params(atype: ast.ActorType) -> set[str]:
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


def _in_library(span: Span) -> bool:
    """Whether a span lies in a shipped library (``<std>``), which a user cannot edit."""
    return span.file.startswith("<")


def _module_dir(file: FsPath) -> FsPath:
    if file.name.startswith("<") and file.name.endswith(">"):
        from .loader import library_path
        return library_path(file.name[1:-1]).parent
    return file.parent


def _whole_ms(value) -> bool:
    return Fraction(value) % 1000 == 0


def _whole_us(value) -> bool:
    return Fraction(value).denominator == 1


def _show(value, t: T.ValueType) -> str:
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
        return str(float(value))
    return str(value)


def check(modules: list[ast.Module], root: ast.Module, diags: Diagnostics) -> CheckedModel | None:
    """Check a loaded model; errors go to ``diags``, the model comes back if none."""
    return Checker(modules, root, diags).run()
