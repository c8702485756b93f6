"""The rules of device types and devices: elaboration of nested devices,
their arguments, claims and data (docs/language.md)."""

from __future__ import annotations

import re
from pathlib import Path as FsPath

from ...core.source import Span, closest, did_you_mean, note
from ...core import types as T
from .. import ast
from ..expressions import ERROR, ExprTyper, Symbol
from ..loader import module_dir
from ..model import Claim, DeviceDatum, DevicePort, PrimitiveDevice, RemoteInfo
from ...core.impl_files import DEVICE_BLOCKS
from .base import C_RESERVED, MAX_RATE, in_library, missing_file, short_name, show_value, whole_ms, whole_us

# `remote overruns K`: the proxy counts them in a byte (docs/remote.md).
MAX_OVERRUN_LIMIT = 255


class DeviceRules:
    # ================================================================ devices

    def check_device_type(self, decl: ast.DeviceType) -> None:
        names: dict[str, Span] = {}
        for item in (*decl.params, *decl.ports, *decl.exports, *decl.parts, *decl.states):
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
        self._check_handler_files(decl)

    def _check_handler_files(self, decl: ast.DeviceType) -> None:
        """``impl BOARD "file.c"`` after the driver, and the state its
        handlers keep (docs/language.md, "Device handlers")."""
        boards: dict[str, Span] = {}
        for impl in decl.impls:
            if impl.board in boards:
                self.error(impl.board_span, f"device type '{decl.name}' has two handler files for board "
                                            f"'{impl.board}'", notes=[note(boards[impl.board], "the first is here")])
                continue
            boards[impl.board] = impl.span
            path = self.handler_path(decl, impl)
            problem = missing_file(path)
            if problem:
                self.error(impl.span, f"handler file '{short_name(impl.file)}' {problem} "
                                      f"(looked at {short_name(str(path), 200)})")
            else:
                self.report_c_file(path, DEVICE_BLOCKS, impl.span, f"handler file '{short_name(impl.file)}'")
        for k, chip in enumerate(decl.chips):
            if k:
                self.error(chip.span, f"device type '{decl.name}' has two chip models (sim \"FILE.c\")",
                           notes=[note(decl.chips[0].span, "the first is here")])
                continue
            path = module_dir(FsPath(self.declaration_files[id(decl)])) / chip.file
            problem = missing_file(path)
            if problem:
                self.error(chip.span, f"chip model '{short_name(chip.file)}' {problem} "
                                      f"(looked at {short_name(str(path), 200)})")
        for st in decl.states:
            self.resolve_type(st.type)
        if decl.states and not decl.impls:
            self.error(decl.states[0].span, f"device type '{decl.name}' has state but no handler files: state "
                                            "is kept for the handlers a model brings",
                       "name them after the driver: driver \"name\" impl BOARD \"file.c\"")
        if not decl.impls:
            return
        for item, what in ([(p, "parameter") for p in decl.params] + [(p, "port") for p in decl.ports]
                           + [(s, "state") for s in decl.states]):
            if item.name in C_RESERVED or item.name.lower().startswith("el_"):
                self.error(item.name_span, f"{what} '{item.name}' of device type '{decl.name}' cannot be named "
                                           "like that: its handlers' C code sees it under its own name",
                           "C keywords, C type names and names starting with el_ are reserved")

    def handler_path(self, decl: ast.DeviceType, impl: ast.DriverImpl) -> FsPath:
        """Where a handler file is: relative to the file declaring the type."""
        return module_dir(FsPath(self.declaration_files[id(decl)])) / impl.file

    def elaborate_device(self, decl: ast.DeviceInstance) -> None:
        """Flatten a device instance into primitive devices and data paths."""
        dtype = self.lookup(decl.type_name, decl.type_span, (ast.DeviceType,), "device type")
        if dtype is None:
            return
        self.top_devices[decl.name] = decl
        args = self.device_args(dtype, decl.args, decl.span, self.const_typer())
        if args is not None and self._elaborate(decl.name, dtype, args, decl.span, ()):
            self.check_safe_values(decl)

    def check_safe_values(self, decl: ast.DeviceInstance) -> None:
        """``safe datum = value`` after a device's arguments: a constant of
        the datum's type, for its `in` data only, each datum once."""
        given: dict[int, Span] = {}
        prefix = decl.name + "."
        for sv in decl.safe:
            name = prefix + sv.datum.text
            datum = self.device_data.get(name)
            if datum is None:
                ins = sorted(k[len(prefix):] for k, d in self.device_data.items()
                             if k.startswith(prefix) and d.port.direction == "in")
                self.error(sv.datum.span, f"device '{decl.name}' has no datum '{sv.datum.text}'",
                           did_you_mean(sv.datum.text, ins) if ins else "it has no in data to give a safe value")
                continue
            if datum.port.direction == "out":
                self.error(sv.datum.span, f"'{name}' is an out datum (read from the device): only in data have "
                                          "safe values")
                continue
            if id(datum) in given:
                self.error(sv.datum.span, f"the safe value of '{name}' is given twice",
                           notes=[note(given[id(datum)], "first given here")])
                continue
            given[id(datum)] = sv.datum.span
            v = self.const_typer().expect_const(sv.value, datum.type, f"the safe value of '{name}'")
            if v.type is None:
                continue
            if datum.type is T.TIME and not whole_ms(v.const):
                self.error(sv.value.span, "a run-time 'time' value counts whole milliseconds")
                continue
            datum.safe = v.const

    def check_remote_settings(self, settings: ast.RemoteSettings) -> None:
        """``remote watchdog T overruns K``: at most one, each setting once."""
        if self.remote is not None:
            self.error(settings.span, "a model has at most one 'remote' declaration",
                       notes=[note(self.remote.decl.span, "the other one")])
            return
        values: dict[str, int] = {}
        typer = self.const_typer()
        for a in settings.attrs:
            if a.key in values:
                self.error(a.span, f"'{a.key}' is given twice")
                continue
            if a.key == "watchdog":
                v = typer.expect_const(a.value, T.TIME, "the watchdog time")
                if v.type is None:
                    continue
                if v.const <= 0 or not whole_us(v.const):
                    self.error(a.value.span, "the watchdog time is a positive whole number of microseconds")
                    continue
            else:
                v = typer.expect_const(a.value, None, "'overruns'")
                if v.type is None:
                    continue
                if not (v.type.is_integer and v.type is not T.TIME) or not 1 <= v.const <= MAX_OVERRUN_LIMIT:
                    self.error(a.value.span, f"'overruns' counts overruns in a row: 1 to {MAX_OVERRUN_LIMIT}, "
                                             f"not {show_value(v.const, v.type)}")
                    continue
            values[a.key] = int(v.const)
        self.remote = RemoteInfo(settings, values.get("watchdog"), values.get("overruns"))

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
                                         f"{', '.join(show_value(c, t) for c in choices)}")
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
                ports[p.name] = DevicePort(p.name, p.direction, t, rate or 1, p.rate is not None)
            claims = []
            for r in dtype.claims:
                claim = self.eval_claim(r, typer, path)
                if claim is not None:
                    claim.span = span  # the device's declaration, not the device type's claim
                    claims.append(claim)
                    self.claims.append(claim)
            states = []
            for st in dtype.states:
                t = self.resolve_type(st.type)
                size = self.eval_rate(st.type.size, typer) if st.type.size is not None else None
                if t is not None:
                    states.append((st.name, t, size))
            handlers = {i.board: str(self.handler_path(dtype, i)) for i in dtype.impls}
            chip = (str(module_dir(FsPath(self.declaration_files[id(dtype)])) / dtype.chips[0].file)
                    if dtype.chips else None)
            device = PrimitiveDevice(path, dtype, dtype.driver, args, ports, claims, span, handlers, states, chip)
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
                part_span = span if in_library(part.span) else part.span
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
        select = None
        if r.select is not None:
            v = typer.expect_const(r.select, None, f"'{r.select_kind}'")
            if v.type is None:
                return None
            if r.select_kind == "addr" and not _whole(v):
                self.error(r.select.span, "a bus address is a non-negative integer, as in addr 0x48")
                return None
            if r.select_kind == "cs" and v.type is not T.STRING:
                self.error(r.select.span, "a chip select is a pin: its name as a string, as in cs \"PB2\"")
                return None
            select = (r.select_kind, v.const)
        if r.index is None:
            m = re.fullmatch(r"([A-Za-z_][A-Za-z0-9_]*?)(\d+)", r.kind)
            if m is None:
                self.error(r.span, f"resource '{r.kind}' needs an index, as in {r.kind}[0]")
                return None
            return Claim(m.group(1), int(m.group(2)), r.span, owner, select)
        v = typer.expect_const(r.index, None, "a resource index")
        if v.type is None:
            return None
        if not (v.type is T.STRING or _whole(v)):
            self.error(r.index.span, "a resource index is a non-negative integer or a pin name string")
            return None
        return Claim(r.kind, v.const, r.span, owner, select)

    def eval_rate(self, e: ast.Expr, typer: ExprTyper) -> int | None:
        v = typer.expect_const(e, None, "a rate")
        if v.type is None:
            return None
        if not (v.type.is_integer and v.type is not T.TIME) or not 1 <= v.const <= MAX_RATE:
            self.error(e.span, f"a rate is a whole number of tokens from 1 to {MAX_RATE}, not {v.const}")
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



def _whole(v) -> bool:
    """A typed constant that is a non-negative integer (not a time)."""
    return v.type.is_integer and v.type is not T.TIME and v.const >= 0
