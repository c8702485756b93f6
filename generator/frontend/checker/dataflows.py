"""The rules of actor types and dataflows: ports, rates, type parameters and
their inference, instances and edges (docs/language.md)."""

from __future__ import annotations

from pathlib import Path as FsPath

from ...core.impl_files import ACTOR_BLOCKS
from ...core.source import Span, closest, did_you_mean, note
from ...core import types as T
from .. import ast
from ..expressions import ERROR, Symbol
from ..loader import module_dir
from ..model import ActorInstanceInfo, ArgValue, DataflowInfo, EdgeInfo, Endpoint, Writer
from .base import C_RESERVED, with_article, kind_name, missing_file, show_value, port_of, short_name, sizing_params


class DataflowRules:
    # ================================================================ actor types

    def check_actor_type(self, decl: ast.ActorType) -> None:
        seen: dict[str, Span] = {}
        if decl.cost is not None:
            self.check_actor_cost(decl)

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
            impl_path = module_dir(base) / decl.impl
            problem = missing_file(impl_path)
            if problem:
                self.error(decl.impl_span, f"implementation file '{short_name(decl.impl)}' {problem} "
                                           f"(looked at {short_name(str(impl_path), 200)})")
            else:
                self.report_c_file(impl_path, ACTOR_BLOCKS, decl.impl_span,
                                   f"implementation file '{short_name(decl.impl)}'")
        elif "step" not in kinds:
            self.error(decl.name_span, f"actor type '{decl.name}' has no 'step' block and no 'impl' file",
                       "add step {{ ... }} with the C code of one firing")
        if not any(p.direction == "out" for p in decl.ports):
            self.error(decl.name_span, f"actor type '{decl.name}' has no output port")

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
        named: set[tuple[str, str]] = set()  # inputs some edge ends at, rejected or not
        sinks: dict[str, Span] = {}
        for edge in decl.edges:
            src = self.endpoint(edge.src, info, "source")
            dst = self.endpoint(edge.dst, info, "destination")
            if src is None or dst is None:
                continue
            # an edge rejected below has its error: its channel or input is
            # not also reported as unconnected
            for end, role in ((dst, "produced"), (src, "consumed")):
                if end.kind == "channel":
                    end.target.named_as.add(role)
            if dst.kind == "actor":
                named.add((dst.target.name, dst.port))
            if src.kind == "actor" and src.target.actor_type and port_of(src.target.actor_type, src.port).direction != "out":
                self.error(edge.src.span, f"'{edge.src.text}' is an input port; an edge starts at an output")
                continue
            if dst.kind == "actor" and port_of(dst.target.actor_type, dst.port).direction != "in":
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
                if port.direction == "in" and (name, port.name) not in named:
                    self.error(instance.decl.name_span, f"input '{name}.{port.name}' is not connected",
                               f"add an edge such as: something -> {name}.{port.name}")

    def check_actor_cost(self, decl: ast.ActorType) -> None:
        """`cost T`: whole nanoseconds from 0.001 us to 1 s, kept in ns."""
        v = self.const_typer().expect_const(decl.cost, T.TIME, f"the cost of actor type '{decl.name}'")
        if v.type is None:
            return
        ns = v.const * 1000  # a time's value is in µs
        if not 1 <= ns <= 10 ** 9 or ns != int(ns):
            self.error(decl.cost_span, f"the cost of actor type '{decl.name}' must be whole nanoseconds from "
                                       f"0.001 us to 1 s", "write: cost 20 us")
            return
        self.actor_costs[decl.name] = int(ns)

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
            if tp.bound is not None and tp.bound not in T.BOUNDS:
                return None  # an unknown bound: reported at the actor type
            if not T.satisfies_bound(t, tp.bound):
                self.error(ref.span, f"'{t}' is not {with_article(tp.bound)} type, as '{atype.name}' requires of {tp.name}",
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
        sizing = sizing_params(atype)
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
            typer = self.typer(lambda p: self.global_symbol(p, allow=("const", "param")), used=used,
                               conversion_hint=_argument_conversion)
            what = f"parameter '{a.name}' of '{inst.name}'"
            v = typer.expect_const(a.value, t, what) if (a.name in sizing or t is T.STRING) else typer.expect(a.value, t, what)
            if v.type is None:
                ok = False
                continue
            choices = self.choice_values(formal, t) if v.is_const else None
            if choices is not None and v.const not in choices:
                self.error(a.value.span, f"{what} must be one of {', '.join(show_value(c, t) for c in choices)}")
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
        self.error(path.part_spans[0], f"'{head}' is {with_article(kind_name(decl))}; an edge joins actor ports, vars, "
                                       "params, channels and device data")
        return None


def _argument_conversion(got: T.ValueType, want: T.ValueType) -> str:
    """The hint for an actor argument of the wrong type: an argument is
    not an edge, so no Cast actor can stand there."""
    return (f"an argument is not converted: declare the param or const it names as '{want}', or give the actor the "
            f"type argument that takes '{got}'")
