"""The C backend's view of a program: IR -> what the model.c template prints.

The shape of the output lives in the Jinja2 templates (templates/*.j2); this
module computes what they print: C names, types, initialisers, and the
straight-line code of schedules, charts and tasks. It reads only the IR.

Buffers (docs/ir.md, "buffers"): in a single-appearance schedule every edge
is linear within one iteration of the innermost loop that contains both of
its ends, so each firing reads and writes at an offset that is an affine
function of the loop counters, as hand-written code would; tokens left by a
delay are moved to the front at the end of that loop body. Other schedules
use circular buffers with run-time indices.
"""

from __future__ import annotations

import types
from dataclasses import dataclass, field
from pathlib import Path

from .. import __version__
from ..core import expr as I
from ..core import types as T
from ..ir.program import ActorSpec, Buffer, Chart, Dataflow, Fire, Item, Loop, Program, Task
from . import multicore
from .dataflow_layout import DataflowLayout, table_schedule
from .c_syntax import C_KIND_ENUM, C_TYPE_ENUM, ExprWriter, c_comment, c_literal, ident, type_param_macros
from ..core.impl_files import split_impl
from .status_view import StatusView, status_views
from .token_moves import copy_tokens, ring_get, ring_put

NONE_STEP = 0xFF
# A schedule with circular buffers (not single-appearance) longer than this
# many runs of firings is emitted as a table walked by a loop (data instead
# of straight-line code: min-buffer schedules of multirate graphs have
# hundreds of appearances).
TABLE_SCHEDULE_RUNS = 24


# ====================================================================== views


@dataclass
class ItemView:
    item: Item
    c_name: str
    c_type: str
    decl: str
    local: str  # field name in a task's local copy
    enum_type: str
    enum_kind: str

    @property
    def addr(self) -> str:
        return self.c_name if self.item.count > 1 else f"&{self.c_name}"


@dataclass
class SpecView:
    spec: ActorSpec
    state_type: str
    state_fields: list[str]
    defines: list[tuple[str, str]]  # (name, replacement) for the code blocks
    step_params: str
    uses: list[str]  # parameters to mark used: C has no unnamed parameters
    start: str | None
    step: str | None
    stop: str | None
    prelude: str | None  # file-scope code of an impl file, once per actor type
    impl_file: str | None


@dataclass
class TaskView:
    task: Task
    struct_fields: list[str]
    release: list[str]
    body: list[str]
    publish: list[str]


@dataclass
class CModel:
    """Everything the templates print."""

    program: Program
    version: str
    board: str
    items: list[ItemView]
    specs: list[SpecView]
    instance_states: list[tuple[str, str, str]]  # (state type, c name, comment)
    buffers: list[str]
    dataflows: list[tuple[str, str, list[str]]]  # (function, comment, body lines)
    charts: list[dict]
    tasks: list[TaskView]
    channels: list[dict]
    boot: list[str]
    shutdown: list[str]
    device_reads: list[tuple[int, str]]  # (reader task mask, read call)
    instants: list[tuple[int, int, int]]
    deadlines: list[int]
    interface_boot: list[str] = field(default_factory=list)  # C statements: start the interfaces
    interface_poll: list[str] = field(default_factory=list)  # C statements: serve them when idle
    status: list[StatusView] = field(default_factory=list)  # the links' fault counters
    probes: bool = False  # the debugger's probes: a debug build of a model with a debug interface
    library: bool = False  # local execution's interfaces library, not a firmware
    multicore: object = None  # codegen/multicore.py's MulticoreView: a multi-core build
    profile: bool = False  # a profiling build (el_profile.h)


class _Builder:
    def __init__(self, program: Program, board, probes: bool = False) -> None:
        self.p = program
        self.board = board
        self.probes = probes  # the debugger's probes of actor firings
        self.profile = False  # a profiling build: every actor firing timed
        self.items = [self._item_view(i) for i in program.items]
        self.buffers: list[str] = []

    # -------------------------------------------------------------- items

    def _item_view(self, item: Item) -> ItemView:
        c_name = f"el_i{item.id}_{ident(item.name)}"
        ctype = item.type.c_name
        if item.count > 1:
            init = ", ".join([c_literal(item.type, item.initial)] * item.count)
            decl = f"{ctype} {c_name}[{item.count}] = {{{init}}};"
        else:
            decl = f"{ctype} {c_name} = {c_literal(item.type, item.initial)};"
        return ItemView(item, c_name, ctype, decl, f"i{item.id}_{ident(item.name)}",
                        C_TYPE_ENUM[item.type.name], C_KIND_ENUM[item.kind])

    def task_of_item_ref(self, task_id: int):
        """Items in expressions of a task read the task's local copy."""
        return lambda e: f"el_t{task_id}.{self.items[e.target].local}"

    # -------------------------------------------------------------- actor specs

    def spec_view(self, spec: ActorSpec) -> SpecView:
        state_type = f"el_spec{spec.id}_{spec.c_name}_state_t"
        fields = []
        defines: list[tuple[str, str]] = []
        for tp, bound in spec.type_bindings.items():
            defines += type_param_macros(tp, bound, spec.type_bindings)
        for name, (t, value) in spec.const_args.items():
            defines.append((name, c_literal(t, value)))
        for name, t, size in spec.states:
            fields.append(f"{t.c_name} {name}{f'[{size}]' if size else ''};")
            defines.append((name, f"(el_self->{name})"))
        if not fields:
            fields.append("uint8_t el_unused; /* C99 wants a member */")
        params = [f"{state_type} *el_self"]
        uses = ["el_self"]
        for port in spec.ports:
            if port.direction == "in":
                params.append(f"const {port.type.c_name} {'*' if port.array else ''}{port.name}")
                uses.append(port.name)
            elif port.array:
                params.append(f"{port.type.c_name} *{port.name}")
                uses.append(port.name)
            else:
                params.append(f"{port.type.c_name} *el_out_{port.name}")
                defines.append((port.name, f"(*el_out_{port.name})"))
                uses.append(f"el_out_{port.name}")
        for name, t in spec.runtime_params.items():
            params.append(f"const {t.c_name} {name}")
            uses.append(name)
        code = dict(spec.code)
        prelude = impl_file = None
        if spec.impl:
            impl_file = spec.impl
            prelude, code = split_impl(Path(spec.impl).read_text(encoding="utf-8"), spec.impl)
            if any(s.type_name == spec.type_name for s in self.p.specs[:spec.id]):
                prelude = None  # emitted with the type's first specialisation
        return SpecView(spec, state_type, fields, defines, ", ".join(params), uses,
                        code.get("start"), code.get("step"), code.get("stop"), prelude, impl_file)

    # -------------------------------------------------------------- dataflows

    def dataflow_code(self, df: Dataflow) -> list[str]:
        """The body of one dataflow's function: its schedule, straight line."""
        layout = self.layout(df)
        linear, bufs, paths, fire_nodes = layout.linear, layout.bufs, layout.paths, layout.fire_nodes
        inst_by_name, ext_by_node, item_ref = layout.insts, layout.exts, layout.item_ref
        lines: list[str] = []
        counters: list[str] = []
        if not linear:
            runs = df.schedule.run_length()
            if len(runs) > TABLE_SCHEDULE_RUNS:
                return table_schedule(self, runs, layout)
        self._emit(df.schedule.body, [], lines, 1, df, bufs, linear, inst_by_name, ext_by_node, item_ref,
                   counters, paths, fire_nodes)
        # Delay tokens of edges linear at the top level move to the front once per activation.
        if linear:
            lines += self.top_level_shifts(layout)
        decls = [f"    {'uint16_t' if count <= 0xFFFF else 'uint32_t'} {name};" for name, count in counters]
        return decls + lines

    def top_level_shifts(self, layout: DataflowLayout) -> list[str]:
        """The delay tokens of edges linear at the top level to the front, after every firing."""
        lines: list[str] = []
        for info in layout.bufs.values():
            if info["level"] == 0 and not info["self_loop"]:
                self._shift(info, lines, 1)
        return lines

    def fire_one(self, layout: DataflowLayout, node: str, index: str | None, ind: str, lines: list[str]) -> None:
        """One firing of ``node`` outside the schedule's loops: in a flat
        single-appearance layout, its firing index within the iteration is
        the C expression ``index``, and its self-loops' delay tokens move
        to the front after it; over circular buffers, ``index`` is None."""
        self._fire(node, [], index, ind, lines, layout.df, layout.bufs, layout.linear, layout.insts, layout.exts,
                   layout.item_ref, layout.paths, layout.fire_nodes)
        for info in layout.bufs.values() if layout.linear else ():
            if info["self_loop"] and info["buf"].src == node:
                self._shift(info, lines, len(ind) // 4)

    def layout(self, df: Dataflow) -> DataflowLayout:
        """Declare the buffers of ``df`` as its schedule places them; where each node sits in its loops."""
        linear = df.schedule.is_single_appearance
        inst_by_name = {self.p.instances[i].name: self.p.instances[i] for i in df.instances}
        ext_by_node = {e.node: e for e in df.externals}
        task = df.task
        item_ref = self.task_of_item_ref(task) if task is not None else (lambda e: "0")
        bufs: dict[int, dict] = {}
        # Where each node sits in the loop tree: the loops (by id) from the top.
        paths: dict[str, list] = {}
        fire_nodes: dict[str, Fire] = {}

        def walk(nodes, path):
            for n in nodes:
                if isinstance(n, Fire):
                    paths[n.actor] = path
                    fire_nodes[n.actor] = n
                else:
                    walk(n.body, path + [n])
        walk(df.schedule.body, [])
        prefix = f"el_df{df.id}"
        for b in df.buffers:
            name = f"{prefix}_b{b.id}"
            info = {"buf": b, "name": name}
            if linear:
                src_path, dst_path = paths.get(b.src, []), paths.get(b.dst, [])
                common = 0
                while common < min(len(src_path), len(dst_path)) and src_path[common] is dst_path[common]:
                    common += 1
                info["level"] = common
                info["self_loop"] = b.src == b.dst
                per_body = self._firings_below(src_path, common, fire_nodes.get(b.src)) * b.prod
                delay = len(b.initial)
                size = per_body + delay if not info["self_loop"] else b.cons + delay
                info["size"] = max(size, 1)
            else:
                info["size"] = max(b.size, 1)
            init = ", ".join(c_literal(b.type, v) for v in b.initial)
            self.buffers.append(f"static {b.type.c_name} {name}[{info['size']}]"
                                + (f" = {{{init}}};" if init else ";") + f" /* {b.src} -> {b.dst} ({c_comment(b.location)}) */")
            if not linear:
                self.buffers.append(f"static uint16_t {name}_rd, {name}_wr = {len(b.initial) % info['size']}u;")
            bufs[b.id] = info
        return DataflowLayout(df, linear, bufs, paths, fire_nodes, inst_by_name, ext_by_node, item_ref)

    @staticmethod
    def _firings_below(path, level, fire) -> int:
        count = fire.count if fire else 1
        for loop in path[level:]:
            count *= loop.count
        return count

    def _index_expr(self, actor: str, level: int, paths, fire_nodes, loop_vars, fire_var) -> str:
        """Firing index of ``actor`` within one body iteration of the loop at ``level``."""
        path = paths[actor]
        terms = []
        for depth in range(level, len(path)):
            stride = self._firings_below(path, depth + 1, fire_nodes[actor])
            var = loop_vars[depth]
            terms.append(var if stride == 1 else f"{var} * {stride}u")
        if fire_nodes[actor].count > 1:
            terms.append(fire_var)
        return " + ".join(terms) if terms else "0u"

    def _shift(self, info: dict, lines: list[str], depth: int) -> None:
        b: Buffer = info["buf"]
        d = len(b.initial)
        if d == 0:
            return
        start = info["size"] - d
        ind = "    " * depth
        lines.append(f"{ind}{{ /* keep the {d} delay token(s) of {b.src} -> {b.dst} */")
        lines.append(f"{ind}    uint16_t el_m;")
        lines.append(f"{ind}    for (el_m = 0u; el_m < {d}u; el_m++) {{ {info['name']}[el_m] = {info['name']}[{start}u + el_m]; }}")
        lines.append(f"{ind}}}")

    def _emit(self, nodes, loop_vars, lines, depth, df, bufs, linear, insts, exts, item_ref, counters, paths,
              fire_nodes):
        ind = "    " * depth
        for n in nodes:
            if isinstance(n, Loop):
                var = f"el_l{len(counters)}"
                counters.append((var, n.count))
                lines.append(f"{ind}for ({var} = 0u; {var} < {n.count}u; {var}++) {{")
                self._emit(n.body, loop_vars + [var], lines, depth + 1, df, bufs, linear, insts, exts, item_ref,
                           counters, paths, fire_nodes)
                level = len(loop_vars) + 1
                if linear:
                    for info in bufs.values():
                        if info["level"] == level and not info["self_loop"] and paths[info["buf"].src] \
                                and paths[info["buf"].src][level - 1] is n:
                            self._shift(info, lines, depth + 1)
                lines.append(f"{ind}}}")
                continue
            fire_var = None
            inner = ind
            if n.count > 1:
                fire_var = f"el_f{len(counters)}"
                counters.append((fire_var, n.count))
                lines.append(f"{ind}for ({fire_var} = 0u; {fire_var} < {n.count}u; {fire_var}++) {{")
                inner = ind + "    "
            self._fire(n.actor, loop_vars, fire_var, inner, lines, df, bufs, linear, insts, exts, item_ref, paths,
                       fire_nodes)
            if linear:
                for info in bufs.values():
                    if info["self_loop"] and info["buf"].src == n.actor:
                        self._shift(info, lines, len(inner) // 4)
            if n.count > 1:
                lines.append(f"{ind}}}")

    def _fire(self, node, loop_vars, fire_var, ind, lines, df, bufs, linear, insts, exts, item_ref, paths,
              fire_nodes):
        ins = [info for info in bufs.values() if info["buf"].dst == node]
        outs = [info for info in bufs.values() if info["buf"].src == node]

        def offset(info, actor, rate, extra=0):
            if info.get("self_loop") and actor == info["buf"].dst and info["buf"].src == actor:
                return "0u" if extra == 0 else f"{extra}u"
            idx = self._index_expr(actor, info["level"], paths, fire_nodes, loop_vars, fire_var)
            base = idx if rate == 1 else f"({idx}) * {rate}u"
            return base if not extra else f"{extra}u + {base}"

        if node in exts:
            ext = exts[node]
            self._fire_external(ext, ins, outs, ind, lines, df, linear, offset, item_ref)
            return
        inst = insts[node]
        spec = self.p.specs[inst.spec]
        args = [f"&el_a{inst.id}_{ident(inst.name)}"]
        decls: list[str] = []
        pre: list[str] = []
        post: list[str] = []
        for port in spec.ports:
            if port.direction == "in":
                info = next(i for i in ins if i["buf"].dst_port == port.name)
                b = info["buf"]
                if linear:
                    pos = offset(info, node, b.cons)
                    args.append(f"&{info['name']}[{pos}]" if port.array else f"{info['name']}[{pos}]")
                else:
                    tmp = f"el_in_{port.name}"
                    decls.append(f"{port.type.c_name} {tmp}[{port.rate}];")
                    pre.append(ring_get(info["name"], info["size"], tmp, port.rate))
                    args.append(tmp if port.array else f"{tmp}[0]")
            else:
                targets = [i for i in outs if i["buf"].src_port == port.name]
                # a buffer holds its destination's type (docs/ir.md): the
                # actor writes in place only into one of its port's type, else
                # into a local array that is converted into each edge
                if linear and len(targets) == 1 and targets[0]["buf"].type == port.type:
                    info = targets[0]
                    pos = offset(info, node, info["buf"].prod, len(info["buf"].initial))
                    args.append(f"&{info['name']}[{pos}]")
                    continue
                tmp = f"el_out_{port.name}"
                decls.append(f"{port.type.c_name} {tmp}[{port.rate}];")
                args.append(tmp)
                for info in targets:
                    if linear:
                        pos = offset(info, node, info["buf"].prod, len(info["buf"].initial))
                        post.append(copy_tokens(f"{info['name']} + {pos}", tmp, port.rate))
                    else:
                        post.append(ring_put(info["name"], info["size"], tmp, port.rate))
        for name, expr in inst.runtime_args.items():
            args.append(ExprWriter(item_ref).write(expr))
        call = f"el_spec{spec.id}_{spec.c_name}_step({', '.join(args)});"
        if self.profile:  # a profiling build times every firing (docs/multicore.md)
            call = f"el_prof_begin(); {call} el_prof_end({inst.id}u);"
        if self.probes:  # the debugger's probe of this firing: the instance's id is its debug actor id
            lines.append(f"{ind}EL_DEBUG_PROBE_ACTOR({inst.id}u);")
        if decls or pre or post:
            lines.append(f"{ind}{{ /* {inst.name} */")
            lines.extend(f"{ind}    {s}" for s in decls + pre)
            lines.append(f"{ind}    {call}")
            lines.extend(f"{ind}    {s}" for s in post)
            lines.append(f"{ind}}}")
        else:
            lines.append(f"{ind}{call} /* {inst.name} */")

    def _fire_external(self, ext, ins, outs, ind, lines, df, linear, offset, item_ref):
        task = df.task
        if ext.kind == "channel":
            local = f"el_t{task}.ch{ext.target}"
            cursor = f"el_t{task}.ch{ext.target}_n"
        else:
            item = self.items[ext.target]
            local = f"el_t{task}.{item.local}"
            cursor = None
        per_fire = 1 if ext.kind == "channel" else self.p.items[ext.target].count
        src = local if (ext.kind == "channel" or per_fire > 1) else f"(&{local})"
        at = f"{cursor}" if cursor else "0u"
        data = f"{src} + {at}"
        if ext.direction == "in":
            for info in outs:
                b = info["buf"]
                if linear:
                    pos = offset(info, ext.node, b.prod, len(b.initial))
                    code = copy_tokens(f"{info['name']} + {pos}", data, per_fire)
                else:
                    code = ring_put(info["name"], info["size"], data, per_fire)
                lines.append(f"{ind}{code} /* {ext.node} */")
            if cursor:
                lines.append(f"{ind}{cursor}++;")
        else:
            info = ins[0]
            if linear:
                pos = offset(info, ext.node, info["buf"].cons)
                code = copy_tokens(data, f"{info['name']} + {pos}", per_fire)
            else:
                code = ring_get(info["name"], info["size"], data, per_fire)
            lines.append(f"{ind}{code} /* {ext.node} */")
            if cursor:
                lines.append(f"{ind}{cursor}++;")

    # -------------------------------------------------------------- charts

    def chart_view(self, chart: Chart) -> dict:
        p = f"el_c{chart.id}"
        task = chart.task
        item_ref = self.task_of_item_ref(task) if task is not None else (lambda e: "0")
        def step_time(e: I.Ref) -> str:
            return f"{p}_elapsed[{e.target}u]"

        def step_active(e: I.Ref) -> str:
            s = chart.steps[e.target]
            return f"({p}_slot[{s.slot}u] == {s.id}u)"

        w = ExprWriter(item_ref, step_time, step_active)
        by_step = {s.id: [t for t in chart.transitions if s.id in t.sources] for s in chart.steps}
        step_fns = []
        for s in chart.steps:
            body = []
            for t in by_step[s.id]:
                others = [chart.steps[o] for o in t.sources if o != s.id]
                conds = [f"({p}_slot[{o.slot}u] == {o.id}u)" for o in others] + [w.write(t.guard)]
                names = ", ".join(chart.steps[x].name for x in t.sources)
                dests = ", ".join(chart.steps[x].name for x in t.targets)
                body.append(f"if ({' && '.join(conds)}) {{ return {t.id}u; }} /* ({names}) -> ({dests}), {c_comment(t.location)} */")
            step_fns.append({"step": s, "body": body})

        def actions(acts):
            out = []
            for a in acts:
                item = self.items[a.target]
                out.append(f"el_t{task}.{item.local} = {w.write(a.value)}; /* {c_comment(a.location)} */")
            return out

        fire = []
        for t in chart.transitions:
            cond = " && ".join(f"el_choice[{chart.steps[s].slot}u] == {t.id}u" for s in t.sources)
            fire.append({"t": t, "cond": cond,
                         "exits": [(chart.steps[s], actions(chart.steps[s].exit)) for s in t.sources],
                         "entries": [(chart.steps[s], actions(chart.steps[s].entry)) for s in t.targets]})
        runs = [(s, [f"el_df{d}_{ident(self.p.dataflows[d].name)}();" for d in s.runs]) for s in chart.steps]
        initial = chart.steps[chart.initial]
        return {"chart": chart, "p": p, "step_fns": step_fns, "fire": fire, "runs": runs,
                "initial": initial, "initial_entry": actions(initial.entry),
                "step_names": ", ".join(f'"{s.name}"' for s in chart.steps),
                "period_ms": chart.period_ms or 0}

    # -------------------------------------------------------------- tasks

    def _exports(self, task: Task, kind: str, target: int) -> list:
        """(index, export) of the node's DDS exports of ``target`` that this
        task's publication (a var) or release (a channel) publishes (ir/dds.py)."""
        return [(k, e) for k, e in enumerate(getattr(self.p, "exports", ()))
                if e.kind == kind and e.target == target and task.id in e.trigger_tasks]

    def task_view(self, task: Task) -> TaskView:
        fields, release, body, publish = [], [], [], []
        for item_id in task.reads:
            iv = self.items[item_id]
            n = iv.item.count
            fields.append(f"{iv.c_type} {iv.local}{f'[{n}]' if n > 1 else ''};")
            if n > 1:
                release.append(f"EL_COPY(el_t{task.id}.{iv.local}, {iv.c_name}, {n}u);")
            else:
                release.append(f"el_t{task.id}.{iv.local} = {iv.c_name};")
        for ch_id in task.channels_in:
            ch = self.p.channels[ch_id]
            fields.append(f"{ch.type.c_name} ch{ch.id}[{ch.tokens_out}];")
            fields.append(f"uint16_t ch{ch.id}_n;")
            release.append(f"el_ch{ch.id}_take(el_t{task.id}.ch{ch.id}); el_t{task.id}.ch{ch.id}_n = 0u;")
            release += [f"el_port_export({k}u, el_t{task.id}.ch{ch.id}); /* DDS: {e.topic} */"
                        for k, e in self._exports(task, "channel", ch.id)]
        for ch_id in task.channels_out:
            ch = self.p.channels[ch_id]
            fields.append(f"{ch.type.c_name} ch{ch.id}[{ch.tokens_in}];")
            fields.append(f"uint16_t ch{ch.id}_n;")
            release.append(f"el_t{task.id}.ch{ch.id}_n = 0u;")
        # A task that latches and publishes nothing (its dataflows' results
        # reach no item) has no local copy: none is declared.
        for kind, ident_ in task.runs:
            if kind == "dataflow":
                body.append(f"el_df{ident_}_{ident(self.p.dataflows[ident_].name)}();")
            else:
                body.append(f"el_c{ident_}_{ident(self.p.charts[ident_].name)}();")
        for item_id in task.writes:
            iv = self.items[item_id]
            n = iv.item.count
            if n > 1:
                publish.append(f"EL_COPY({iv.c_name}, el_t{task.id}.{iv.local}, {n}u);")
            else:
                publish.append(f"{iv.c_name} = el_t{task.id}.{iv.local};")
        for item_id in task.writes:
            iv = self.items[item_id]
            publish += [f"el_port_export({k}u, {'' if iv.item.count > 1 else '&'}{iv.c_name}); /* DDS: {e.topic} */"
                        for k, e in self._exports(task, "var", item_id)]
        for ch_id in task.channels_out:
            publish.append(f"el_ch{ch_id}_put(el_t{task.id}.ch{ch_id});")
        for kind, ident_ in task.runs:
            if kind == "chart":
                publish.append(f"el_c{ident_}_publish();")
        for dev in self.p.devices:
            if dev.written_by == task.id:
                publish.append(self.board.device_call(dev, "write") + f" /* {dev.path} */")
        return TaskView(task, fields, release, body, publish)


def build_view(program: Program, board, library: bool = False, probes: bool = False, plan=None,
               profile: bool = False) -> CModel:
    """The view of a program that the C templates print (``library``: for
    local execution's interfaces library rather than a firmware;
    ``probes``: a debug build with a debug interface, whose actor firings
    call the debugger's probe; ``plan``: a multi-core plan
    (ir/multicore.py), printed when anything in it is parallel;
    ``profile``: every actor firing timed, for ``easylab analyze --profile``)."""
    b = _Builder(program, board, probes)
    b.profile = profile
    specs = [b.spec_view(s) for s in program.specs]
    states = [(specs[i.spec].state_type, f"el_a{i.id}_{ident(i.name)}",
               f"{program.dataflows[i.dataflow].name}.{i.name} ({c_comment(i.location)})") for i in program.instances]
    mc = multicore.MulticoreView(plan.cores) if plan is not None and plan.parallel else None
    parallel = {fp.dataflow.id: fp for fp in plan.dataflows if fp.parallel} if mc else {}
    dataflows = []
    for df in program.dataflows:
        comment = f"dataflow {df.name} ({c_comment(df.location)}), schedule {df.schedule.text()}"
        if df.id in parallel:
            job = multicore.JOB_TASKS + 1 + len(mc.jobs)
            body = multicore.dataflow_functions(b, parallel[df.id], job, mc)
            comment += f", its firings on {mc.cores} cores"
        else:
            body = b.dataflow_code(df)
        dataflows.append((f"el_df{df.id}_{ident(df.name)}", comment, body))
    charts = [b.chart_view(c) for c in program.charts]
    tasks = [b.task_view(t) for t in program.tasks]
    channels = [{"ch": c, "init": ", ".join(c_literal(c.type, v) for v in c.initial)} for c in program.channels]
    boot = []
    for dev in program.devices:
        boot.append(board.device_call(dev, "open") + f" /* {dev.path} */")
    for dev in program.devices:
        boot.append(board.device_call(dev, "start") + f" /* {dev.path} */")
    for i in program.instances:
        spec = specs[i.spec]
        if spec.start:
            boot.append(f"el_spec{spec.spec.id}_{spec.spec.c_name}_start(&el_a{i.id}_{ident(i.name)});")
    shutdown = []
    for i in program.instances:
        spec = specs[i.spec]
        if spec.stop:
            shutdown.append(f"el_spec{spec.spec.id}_{spec.spec.c_name}_stop(&el_a{i.id}_{ident(i.name)});")
    for dev in program.devices:
        shutdown.append(board.device_call(dev, "stop") + f" /* {dev.path} */")
    for dev in program.devices:
        shutdown.append(board.device_call(dev, "close") + f" /* {dev.path} */")
    reads = [(sum(1 << t for t in dev.read_by), board.device_call(dev, "read") + f" /* {dev.path} */")
             for dev in program.devices if dev.read_by]
    instants = [(i.tick, sum(1 << t for t in i.publish), sum(1 << t for t in i.release)) for i in program.instants]
    deadlines = [t.deadline for t in program.tasks]
    if mc:
        multicore.group_table(plan, len(program.tasks), mc)
        boot.append(f"el_threads_start({mc.cores}u); /* the other cores' threads, once */")
        shutdown.insert(0, "el_threads_stop();")
    return CModel(program, __version__, board.name, b.items, specs, states, b.buffers, dataflows, charts, tasks,
                  channels, boot, shutdown, reads, instants, deadlines, status=status_views(program, library),
                  probes=probes, library=library, multicore=mc, profile=profile)


def spec_view(spec: ActorSpec) -> SpecView:
    """The view of one actor specialisation on its own (for the
    interpreter's plug-ins: templates/actor.c.j2 prints it), with its impl
    file's file-scope code."""
    return _Builder(types.SimpleNamespace(items=[], specs=[spec]), board=None).spec_view(spec)
