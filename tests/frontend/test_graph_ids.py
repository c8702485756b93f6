"""The stable element ids of `easylab graph`'s drawings (generator/frontend/
graph.py), which the online mode draws the running program on: every step,
transition, actor instance, dataflow edge, device, var and param has its
id in the SVG, the ids are unique, derived from the model's paths, and the
same from one run to the next; checked on the examples and on seeded random
models (tests/crosscheck/modelgen.py)."""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from html import unescape
from pathlib import Path

import pytest

from easylab.frontend.graph import render_dot
from easylab.pipeline import check_file

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests" / "crosscheck"))
from modelgen import generate  # noqa: E402

EXAMPLES = ["pneumatic_cylinder", "blink", "line_follower", "pt100_sensor"]
SEEDS = range(1, 13)


def expected_ids(model) -> set[str]:
    """The ids every element of a checked model must have, from the model."""
    ids = {f"{d.kind}:{d.name}" for d in model.data.values()}
    ids |= {f"device:{d.path}" for d in model.devices}
    ids |= {f"task:{t}" for t in model.tasks}
    for df in model.dataflows.values():
        ids |= {f"actor:{df.name}.{name}" for name in df.instances}
        ids |= {f"edge:{df.name}/{e.src.label}->{e.dst.label}" for e in df.edges}
        ids |= {f"ext:{df.name}/{end.label}" for e in df.edges for end in (e.src, e.dst) if end.kind != "actor"}
    for chart in model.charts.values():
        ids |= {f"step:{chart.name}.{s}" for s in chart.steps}
        ids |= {f"transition:{chart.name}.{t.index}" for t in chart.transitions}
    return ids


def svg_ids(dot: str) -> list[str]:
    """The element ids in the SVG Graphviz draws from `dot` (Graphviz's own
    node1, edge1, clust1, graph0 left out)."""
    svg = subprocess.run([shutil.which("dot"), "-Tsvg"], input=dot.encode(), capture_output=True,
                         check=True, timeout=120).stdout.decode()
    ids = [unescape(i) for i in re.findall(r'<g id="([^"]+)"', svg)]
    return [i for i in ids if not re.fullmatch(r"(node|edge|clust|graph|a_node|a_edge)\d+", i)]


def models():
    for name in EXAMPLES:
        yield name, check_file(ROOT / "examples" / f"{name}.elab").model
    for seed in SEEDS:
        text = generate(seed, "atmega2560").text
        yield f"seed {seed}", check_file(f"rand{seed}.elab", text=text).model


@pytest.mark.parametrize("name,model", list(models()), ids=lambda v: v if isinstance(v, str) else "")
def test_every_element_has_a_unique_stable_id_in_the_svg(name, model):
    assert model is not None, name
    dot = render_dot(model)
    assert render_dot(model) == dot, "the drawing differs from one run to the next"
    ids = svg_ids(dot)
    assert len(ids) == len(set(ids)), f"{name}: ids drawn twice: {sorted(i for i in ids if ids.count(i) > 1)}"
    missing = expected_ids(model) - set(ids)
    assert not missing, f"{name}: elements without their id: {sorted(missing)}"
    # Parallel branches' bars: their edges carry the transition's id with .from/.to
    extra = {i for i in set(ids) - expected_ids(model) if not re.fullmatch(r"transition:.+\.\d+\.(from|to)\..+", i)}
    assert not extra, f"{name}: ids that name no element: {sorted(extra)}"


def test_the_ids_are_the_models_paths():
    model = check_file(ROOT / "examples" / "pneumatic_cylinder.elab").model
    ids = set(svg_ids(render_dot(model)))
    assert {"step:Cylinder.Extending", "transition:Cylinder.0", "actor:PositionControl.pid",
            "edge:PositionControl/pid.y->drive", "ext:PositionControl/position.value", "device:end_out",
            "var:drive", "param:kp", "task:control"} <= ids
