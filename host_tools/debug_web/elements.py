"""The model's drawing for the online mode, and what each of its elements
is in the debug map.

The drawing is `easylab graph`'s (generator/frontend/graph.py), rendered
once when the server starts. Its element ids are the model's paths
(``step:Cylinder.Extending``, ``edge:PositionControl/pid.y->drive``, ...),
so an element is matched to the map by its id alone: its probe point (where
a click sets a breakpoint), the items whose values are drawn on it, and for
a step its chart's ``CHART.active`` item.
"""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

from ..debug_map import DebugMap
from ..debug_protocol import K

ID_RE = re.compile(r'<g id="([a-z]+:[^"]+)"')


class DrawingError(Exception):
    """The model cannot be drawn (one line: why)."""


def render_svg(model_path: Path) -> str:
    """The model's drawing as SVG text (its checker's errors as DrawingError)."""
    from ...frontend.graph import render_dot
    from ...pipeline import check_file

    result = check_file(model_path)
    if result.model is None:
        raise DrawingError(f"{model_path} has errors:\n{result.report()}")
    exe = shutil.which("dot")
    if exe is None:
        raise DrawingError("Graphviz's 'dot' is not installed (Debian package: graphviz)")
    proc = subprocess.run([exe, "-Tsvg"], input=render_dot(result.model).encode("utf-8"), capture_output=True,
                          timeout=120)
    if proc.returncode != 0:
        raise DrawingError(f"dot failed: {proc.stderr.decode(errors='replace').strip()}")
    svg = proc.stdout.decode("utf-8")
    return svg[svg.index("<svg"):]  # without the XML prolog and doctype: it goes inside the page


def _unescape(text: str) -> str:
    return text.replace("&#45;", "-").replace("&gt;", ">").replace("&lt;", "<").replace("&amp;", "&")


def element_ids(svg: str) -> list[str]:
    """The model elements' ids in a drawing, in drawing order."""
    return [_unescape(m) for m in ID_RE.findall(svg)]


def elements(dmap: DebugMap, ids: list[str], guards=None) -> dict[str, dict]:
    """For each element id: ``point`` ([kind, a, b] of its probe point, or
    None), ``items`` (the ids of the map items drawn on it; for a
    transition, those its guard reads, from `guards`: a GuardValues), and
    for a step ``chart_item`` and ``step`` (it is active when the chart's
    item holds it); for a step and a transition ``fired_item``, the
    chart's last fired transition (polled with the chart), and for a
    transition ``transition`` (it fired last when that item holds it)."""
    charts = {c["name"]: c for c in dmap.charts}
    actors = {a["name"]: a for a in dmap.actors}
    tasks = {t["name"]: t for t in dmap.tasks}
    by_name = dmap.by_name
    out: dict[str, dict] = {}
    for el in ids:
        kind, _, path = el.partition(":")
        info: dict = {"point": None, "items": []}
        if kind == "step":
            chart_name, _, step_name = path.rpartition(".")
            chart = charts.get(chart_name)
            step = next((s for s in chart["steps"] if s["name"] == step_name), None) if chart else None
            if step is not None:
                info["point"] = [K.P_STEP, chart["id"], step["id"]]
                info["items"] = _ids(by_name, f"{path}.time")
                info["chart_item"] = by_name[f"{chart_name}.active"].id if f"{chart_name}.active" in by_name else None
                info["fired_item"] = _fired_item(by_name, chart_name)
                info["step"] = step["id"]
                info["location"] = step.get("location")
        elif kind == "transition":
            m = re.fullmatch(r"(.+)\.(\d+)(\.(from|to)\..+)?", path)
            chart = charts.get(m.group(1)) if m else None
            tr = next((t for t in chart["transitions"] if t["id"] == int(m.group(2))), None) if chart else None
            if tr is not None:
                info["point"] = [K.P_TRANSITION, chart["id"], tr["id"]]
                info["location"] = tr.get("location")
                info["items"] = guards.needs(el) if guards is not None else []
                info["fired_item"] = _fired_item(by_name, m.group(1))
                info["transition"] = tr["id"]
        elif kind == "actor":
            actor = actors.get(path)
            if actor is not None:
                info["point"] = [K.P_ACTOR, actor["id"], 0]
                info["items"] = list(actor.get("states", []))
                info["location"] = actor.get("location")
        elif kind == "task":
            task = tasks.get(path)
            if task is not None:
                info["point"] = [K.P_TASK, task["id"], 0]
                info["location"] = task.get("location")
        elif kind == "edge":
            # An edge shows the value of its var, param or device datum end
            # (the one the dataflow writes, else the one it reads).
            src, _, dst = path.split("/", 1)[1].partition("->")
            info["items"] = _ids(by_name, dst)[:1] or _ids(by_name, src)[:1]
        elif kind == "ext":
            info["items"] = _ids(by_name, path.split("/", 1)[1])
        elif kind in ("var", "param"):
            info["items"] = _ids(by_name, path)
        elif kind == "device":
            info["items"] = [it.id for it in dmap.items
                             if it.kind in ("dev_out", "dev_in", "dev_state") and it.name.startswith(path + ".")]
        if info["point"] is not None or info["items"]:
            out[el] = info
    return out


def _fired_item(by_name: dict, chart_name: str) -> int | None:
    """The id of a chart's `CHART.fired` item (None: a map without it)."""
    item = by_name.get(f"{chart_name}.fired")
    return item.id if item is not None else None


def _ids(by_name: dict, name: str) -> list[int]:
    return [by_name[name].id] if name in by_name else []


def model_file(dmap: DebugMap, given: str | None) -> Path:
    """The model's file: `given`, else the file the map's locations name
    (relative to the working folder, then to the map's folder and its parents)."""
    if given is not None:
        path = Path(given)
        if not path.is_file():
            raise DrawingError(f"--model {given}: no such file")
        return path
    named = next((c["location"] for c in dmap.charts + dmap.tasks + dmap.actors if c.get("location")), None)
    if named is None:
        named = next((it.location for it in dmap.items if it.location != "?"), None)
    if named is not None:
        rel = Path(named.rsplit(":", 1)[0])
        for base in [Path.cwd(), *Path(dmap.path).resolve().parents]:
            if (base / rel).is_file():
                return base / rel
    raise DrawingError(f"cannot find the model of {dmap.path} ({named or 'no locations'}): give it with --model FILE")
