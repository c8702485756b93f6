"""Graphviz drawings of a checked model: devices, dataflows and charts.

One DOT document with a cluster per part of the model: the device tree
(composed devices as nested clusters, primitive devices with their data and
claims), each dataflow (actors with rates on their edges, external data as
ellipses) and each chart (steps, transitions with guards, bars for parallel
divergence and convergence), and the model's vars and params.

Every element carries a stable ``id`` derived from its path in the model
(Graphviz writes it on the element's ``<g>`` in SVG), which the online mode
(``easylab-debug web``) uses to draw the running program on the drawing:
``step:CHART.STEP``, ``transition:CHART.N`` (N: the transition's index; a
bar's edges add ``.from.STEP`` or ``.to.STEP``), ``actor:DATAFLOW.INSTANCE``,
``edge:DATAFLOW/SRC->DST``, ``ext:DATAFLOW/NAME`` (a var, param, device datum
or channel drawn in a dataflow), ``device:PATH``, ``var:NAME``,
``param:NAME``, ``task:NAME``. ``element_locations`` maps each id to its
declaration's span (``easylab graph --serve`` shows it on a click).
"""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

from ..core.source import Span
from . import ast
from .model import CheckedModel, PrimitiveDevice

_RENDERED = {".svg": "svg", ".png": "png", ".pdf": "pdf"}


def _q(text: str) -> str:
    """A DOT string. Labels use real newlines; record labels may carry DOT's
    own escapes (\\l), so backslashes are left alone: model names never hold one."""
    return '"' + text.replace('"', '\\"').replace("\n", "\\n") + '"'


def _id(element_id: str) -> str:
    """The DOT attribute giving an element its stable id (see the module's docstring)."""
    return f"id={_q(element_id)}"


# The elements' ids (see the module's docstring), one function each, for
# the drawing and for element_locations.
def task_id(task) -> str:
    return f"task:{task.name}"


def data_id(data) -> str:
    return f"{data.kind}:{data.name}"


def device_id(path: str) -> str:
    return f"device:{path}"


def actor_id(df, name: str) -> str:
    return f"actor:{df.name}.{name}"


def external_id(df, end) -> str:
    return f"ext:{df.name}/{end.label}"


def edge_id_of(df, edge) -> str:
    return f"edge:{df.name}/{edge.src.label}->{edge.dst.label}"


def step_id(chart, step) -> str:
    return f"step:{chart.name}.{step.name}"


def transition_id(chart, transition) -> str:
    return f"transition:{chart.name}.{transition.index}"


def element_locations(model: CheckedModel) -> dict[str, Span]:
    """Where each element of the drawing is declared: its id -> the span of
    its declaration (an external datum: where the dataflow names it first)."""
    where: dict[str, Span] = {}
    for dev in model.devices:
        where[device_id(dev.path)] = dev.span
    for df in model.dataflows.values():
        for name, inst in df.instances.items():
            where[actor_id(df, name)] = inst.decl.span
        for e in df.edges:
            where[edge_id_of(df, e)] = e.decl.span
            for end in (e.src, e.dst):
                if end.kind != "actor":
                    where.setdefault(external_id(df, end), end.path.span)
    for chart in model.charts.values():
        for step in chart.steps.values():
            where[step_id(chart, step)] = step.decl.span
        for tr in chart.transitions:
            where[transition_id(chart, tr)] = tr.decl.span
    for data in model.data.values():
        where[data_id(data)] = data.decl.span
    for task in model.tasks.values():
        where[task_id(task)] = task.decl.span
    return where


def _expr_text(e: ast.Expr) -> str:
    if isinstance(e, ast.Path):
        return e.text
    if isinstance(e, ast.IntLit):
        return str(e.value)
    if isinstance(e, (ast.RealLit, ast.DurationLit)):
        return e.text
    if isinstance(e, ast.BoolLit):
        return "true" if e.value else "false"
    if isinstance(e, ast.StringLit):
        return f'"{e.value}"'
    if isinstance(e, ast.Unary):
        return f"{e.op}{' ' if e.op == 'not' else ''}{_expr_text(e.operand)}"
    if isinstance(e, ast.Binary):
        return f"({_expr_text(e.left)} {e.op} {_expr_text(e.right)})"
    return "?"


class _Dot:
    def __init__(self) -> None:
        self.lines: list[str] = []
        self.depth = 1

    def add(self, line: str) -> None:
        self.lines.append("  " * self.depth + line)

    def open(self, cluster_id: str, label: str, style: str = "rounded") -> None:
        self.add(f"subgraph {_q('cluster_' + cluster_id)} {{")
        self.depth += 1
        self.add(f"label={_q(label)}; style={style}; fontname=Helvetica;")

    def close(self) -> None:
        self.depth -= 1
        self.add("}")


def render_dot(model: CheckedModel) -> str:
    """The whole model as one Graphviz DOT document."""
    dot = _Dot()
    title = model.name + (f": {model.title}" if model.title else "")
    title = title.replace("\\", "/")
    dot.lines.append(f"digraph {_q(model.name)} {{")
    dot.add(f"label={_q(title)}; labelloc=t; fontname=Helvetica; compound=true; rankdir=LR;")
    dot.add("node [fontname=Helvetica, fontsize=10]; edge [fontname=Helvetica, fontsize=9];")
    _devices(dot, model)
    for df in model.dataflows.values():
        _dataflow(dot, df)
    for chart in model.charts.values():
        _chart(dot, chart)
    _data(dot, model)
    if model.tasks:
        dot.open("tasks", "tasks")
        for task in model.tasks.values():
            runs = ", ".join(r.name for r in task.runs)
            period = _duration(task.period_us)
            dot.add(f"{_q('task.' + task.name)} [shape=note, {_id(task_id(task))}, "
                    f"label={_q(f'{task.name} every {period}: {runs}')}];")
        dot.close()
    dot.lines.append("}")
    return "\n".join(dot.lines) + "\n"


def _duration(us) -> str:
    for unit, scale in (("s", 1_000_000), ("ms", 1000)):
        if us % scale == 0:
            return f"{us // scale} {unit}"
    return f"{us} us"


def _data(dot: _Dot, model: CheckedModel) -> None:
    """The vars and params, one node each (where their values are shown online)."""
    if not model.data:
        return
    dot.open("data", "vars and params")
    for data in model.data.values():
        dot.add(f"{_q('data.' + data.name)} [shape=plaintext, {_id(data_id(data))}, "
                f"label={_q(f'{data.kind} {data.name}: {data.type}')}];")
    dot.close()


def _devices(dot: _Dot, model: CheckedModel) -> None:
    if not model.devices:
        return
    dot.open("devices", "devices")
    tree: dict = {}
    for dev in model.devices:
        node = tree
        for part in dev.path.split(".")[:-1]:
            node = node.setdefault(part, {})
        node[dev.path.split(".")[-1]] = dev
    _device_tree(dot, tree, "")
    dot.close()


def _device_tree(dot: _Dot, tree: dict, prefix: str) -> None:
    for name, child in tree.items():
        path = f"{prefix}{name}"
        if isinstance(child, PrimitiveDevice):
            data = "\\l".join(f"{p.direction} {p.name}: {p.type}" + (f" rate {p.rate}" if p.rate != 1 else "")
                              for p in child.ports.values())
            claims = ", ".join(str(c) for c in child.claims)
            label = f"{{{name} ({child.type.name})|driver {child.driver}|{data}\\l|{claims}}}"
            dot.add(f"{_q('dev.' + path)} [shape=record, {_id(device_id(path))}, label={_q(label)}];")
        else:
            dot.open("dev_" + path, path)
            _device_tree(dot, child, path + ".")
            dot.close()


def _dataflow(dot: _Dot, df) -> None:
    dot.open("df_" + df.name, f"dataflow {df.name}")
    prefix = f"df.{df.name}."
    for name, inst in df.instances.items():
        targs = ", ".join(str(t) for t in inst.type_bindings.values())
        label = f"{name}\n{inst.actor_type.name}" + (f"<{targs}>" if targs else "")
        dot.add(f"{_q(prefix + name)} [shape=box, style=rounded, {_id(actor_id(df, name))}, "
                f"label={_q(label)}];")
    externals: set[str] = set()
    for e in df.edges:
        ends = []
        for end in (e.src, e.dst):
            if end.kind == "actor":
                ends.append(prefix + end.target.name)
            else:
                node = prefix + "ext." + end.label
                if node not in externals:
                    externals.add(node)
                    shape = {"channel": "cds", "device": "ellipse"}.get(end.kind, "oval")
                    dot.add(f"{_q(node)} [shape={shape}, {_id(external_id(df, end))}, "
                            f"label={_q(end.label)}, style=dashed];")
                ends.append(node)
        rates = []
        if e.src.kind == "actor" and e.dst.kind == "actor":
            rates.append(f"{e.src.port} {e.src.rate}:{e.dst.rate} {e.dst.port}")
        if e.initial_tokens:
            rates.append(f"{len(e.initial_tokens)} D")
        label = f", label={_q('  '.join(rates))}" if rates else ""
        edge_id = _id(edge_id_of(df, e))
        dot.add(f"{_q(ends[0])} -> {_q(ends[1])} [{edge_id}{label}];")
    if not df.instances and not df.edges:
        dot.add(f"{_q(prefix + 'empty')} [shape=plaintext, label=\"(empty)\"];")
    dot.close()


def _chart(dot: _Dot, chart) -> None:
    dot.open("chart_" + chart.name, f"chart {chart.name}")
    prefix = f"chart.{chart.name}."
    for step in chart.steps.values():
        actions = [f"P1 {a.target.text} = {_expr_text(a.value)}" for a in step.decl.entry]
        actions += [f"N {r.name}" for r in step.decl.runs]
        actions += [f"P0 {a.target.text} = {_expr_text(a.value)}" for a in step.decl.exit]
        shape = "doubleoctagon" if step.decl.initial else "box"
        label = step.name + ("\n" + "\n".join(actions) if actions else "")
        dot.add(f"{_q(prefix + step.name)} [shape={shape}, {_id(step_id(chart, step))}, "
                f"label={_q(label)}];")
    for tr in chart.transitions:
        guard = _expr_text(tr.decl.guard)
        tid = transition_id(chart, tr)
        if len(tr.sources) == 1 and len(tr.targets) == 1:
            dot.add(f"{_q(prefix + tr.sources[0].name)} -> {_q(prefix + tr.targets[0].name)} "
                    f"[{_id(tid)}, label={_q(guard)}];")
            continue
        bar = f"{prefix}t{tr.index}"
        dot.add(f"{_q(bar)} [shape=box, style=filled, fillcolor=black, height=0.05, width=1, {_id(tid)}, label=\"\"];")
        for s in tr.sources:
            dot.add(f"{_q(prefix + s.name)} -> {_q(bar)} [{_id(f'{tid}.from.{s.name}')}"
                    + (f", label={_q(guard)}" if len(tr.sources) == 1 else "") + "];")
        for t in tr.targets:
            dot.add(f"{_q(bar)} -> {_q(prefix + t.name)} [{_id(f'{tid}.to.{t.name}')}"
                    + (f", label={_q(guard)}" if len(tr.sources) > 1 and t is tr.targets[0] else "") + "];")
    dot.close()


def write_graph(dot: str, output: Path) -> None:
    """Write DOT text, or render it with Graphviz for .svg/.png/.pdf outputs."""
    fmt = _RENDERED.get(output.suffix.lower())
    if fmt is None:
        if output.suffix.lower() not in (".dot", ".gv"):
            raise RuntimeError(f"{output}: unknown output format '{output.suffix}' (use .dot, .svg, .png or .pdf)")
        output.write_text(dot, encoding="utf-8")
        return
    output.write_bytes(run_dot(dot, fmt))


def run_dot(dot: str, fmt: str) -> bytes:
    """The drawing Graphviz's dot makes of DOT text in format ``fmt`` (svg,
    png, pdf); RuntimeError when dot is missing or fails."""
    exe = shutil.which("dot")
    if exe is None:
        raise RuntimeError("Graphviz's 'dot' is not installed (Debian package: graphviz); "
                           "write DOT instead with -o model.dot")
    proc = subprocess.run([exe, f"-T{fmt}"], input=dot.encode("utf-8"), capture_output=True, timeout=120)
    if proc.returncode != 0:
        raise RuntimeError(f"dot failed: {proc.stderr.decode(errors='replace').strip()}")
    return proc.stdout
