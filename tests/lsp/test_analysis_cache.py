"""The server re-analyses only the dataflows an edit changed (its SDF
analysis cache, docs/editors.md), and what it finds after any sequence of
edits is what `easylab check` finds for the same text from scratch: the
same diagnostics and, for a good model, the same lowered program."""

from __future__ import annotations

import gc
import json
import re
import sys
import weakref
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from lsp_helpers import EXAMPLES, ROOT
from mutations import HypothesisChooser, mutate

from easylab.ir.lower import lower
from easylab.ir.program import to_json
from easylab.lsp.workspace import Workspace
from easylab.pipeline import check_file

sys.path.insert(0, str(ROOT / "bench"))
from bench_frontend import generate_model  # noqa: E402

FLOWS = 6  # dataflows of the generated model (50 actors each)


def from_scratch(path: Path, text: str):
    """(diagnostics, lowered program as JSON or None) of `easylab check` on the text."""
    result = check_file(path, text=text)
    program = json.dumps(to_json(lower(result.model, result.timing)), sort_keys=True) if result.model else None
    return result.diagnostics.sorted(), program


def in_workspace(workspace: Workspace, path: Path, text: str):
    """The same, from the server's workspace after the edit."""
    result = workspace.open(path, text).result
    program = json.dumps(to_json(lower(result.model, result.timing)), sort_keys=True) if result.model else None
    return result.diagnostics.sorted(), program


def flow_body(text: str, n: int) -> tuple[int, int]:
    """Where dataflow Flow<n> of the generated model stands in its text."""
    start = text.index(f"dataflow Flow{n} {{")
    return start, text.index("\n}", start)


def rename_instances(text: str, n: int) -> str:
    """Flow<n> with its actor instances renamed: a new SDF graph for that dataflow only."""
    start, end = flow_body(text, n)
    return text[:start] + re.sub(r"\ba(\d+)\b", r"b\1", text[start:end]) + text[end:]


def test_an_edit_to_one_dataflow_reanalyses_that_dataflow_only(tmp_path):
    path = tmp_path / "big.elab"
    text = generate_model(50 * FLOWS)
    workspace = Workspace()
    cache = workspace.sdf_cache
    workspace.open(path, text)
    assert cache.analyses == FLOWS
    # a comment, then a blank line that moves every later dataflow: nothing to analyse
    commented = text.replace("dataflow Flow3 {", "dataflow Flow3 {  // edited", 1)
    moved = commented.replace("dataflow Flow0 {", "\ndataflow Flow0 {", 1)
    for edited in (commented, moved):
        assert in_workspace(workspace, path, edited) == from_scratch(path, edited)
    assert cache.analyses == FLOWS
    # a new graph for one dataflow: that one analysed, the others remembered
    renamed = rename_instances(moved, 2)
    assert in_workspace(workspace, path, renamed) == from_scratch(path, renamed)
    assert cache.analyses == FLOWS + 1
    assert cache.hits == 3 * FLOWS - 1
    # back to the earlier text: every graph is one the cache has seen
    assert in_workspace(workspace, path, moved) == from_scratch(path, moved)
    assert cache.analyses == FLOWS + 1


def _moved(text: str, choose: HypothesisChooser) -> str:
    """An edit that keeps the model's meaning and moves the text after it:
    blank lines or a comment line inserted at a line break."""
    lines = text.split("\n")
    i = choose.integer(0, len(lines) - 1)
    lines.insert(i, choose.pick(["", "", "// note", "/* a\n   b */"]))
    return "\n".join(lines)


SEEDS = [(p, p.read_text(encoding="utf-8")) for p in EXAMPLES] + [(None, generate_model(150))]


@settings(max_examples=60, deadline=None, derandomize=True, suppress_health_check=list(HealthCheck))
@given(st.data())
def test_after_random_edits_the_workspace_finds_what_easylab_check_finds(data):
    example, original = data.draw(st.sampled_from(SEEDS))
    # an example is edited in place of a copy beside it (its imports and driver files)
    path = example.parent / f".cache_edit_{example.stem}.elab" if example else ROOT / "bench" / ".cache_edit_big.elab"
    workspace = Workspace()
    workspace.open(path, original)
    text = original
    for _ in range(data.draw(st.integers(1, 4))):
        choose = HypothesisChooser(data.draw)
        edit = data.draw(st.sampled_from(["mutate", "move", "move", "undo"]))
        text = original if edit == "undo" else mutate(text, choose) if edit == "mutate" else _moved(text, choose)
        assert in_workspace(workspace, path, text) == from_scratch(path, text), text


def test_diagnostics_do_not_wait_for_the_name_index(tmp_path):
    path = tmp_path / "big.elab"
    analysis = Workspace().open(path, generate_model(100))
    analysis.diagnostics_by_file()
    assert "index" not in vars(analysis)  # not built yet
    assert analysis.index.globals["Flow0"].kind == "dataflow"  # built on first use


@pytest.mark.parametrize("collector", ["on", "off"])
def test_an_edit_frees_the_model_it_replaces_by_a_young_collection(tmp_path, collector):
    """The collector on: freed at the next edit, not later by a full
    collection; off: the workspace's own young collection frees it."""
    path = tmp_path / "big.elab"
    text = generate_model(300)
    workspace = Workspace()
    workspace.open(path, text)  # its model goes to the oldest generation with the parsed files
    workspace.open(path, text + "// the first edit\n")
    was_enabled = gc.isenabled()
    if collector == "off":
        gc.disable()
    try:
        for n in range(4):
            # a dataflow and its actor instances refer to each other: a cycle
            flow = workspace.analyses[path.resolve()].result.model.dataflows["Flow0"]
            assert next(iter(flow.instances.values())).dataflow is flow
            previous = weakref.ref(flow)
            del flow
            workspace.open(path, text + f"// edit {n}\n").diagnostics_by_file()
            assert previous() is None  # freed already
    finally:
        if was_enabled:
            gc.enable()


def test_a_newly_opened_model_s_parsed_files_start_in_the_oldest_generation(tmp_path):
    analysis = Workspace().open(tmp_path / "big.elab", generate_model(100))
    declaration = analysis.module(tmp_path / "big.elab").declarations[-1]
    assert any(o is declaration for o in gc.get_objects(generation=2))


def test_no_collection_runs_during_a_check(tmp_path):
    path = tmp_path / "big.elab"
    text = generate_model(300)
    workspace = Workspace()
    workspace.open(path, text)
    generations = []

    def watch(phase, info):
        if phase == "start":
            generations.append(info["generation"])

    gc.callbacks.append(watch)
    try:
        workspace.open(path, text + "// edited\n")
    finally:
        gc.callbacks.remove(watch)
    # the workspace's young collection before the check, at most one of the new objects after it
    assert generations[0] == 1 and generations[1:] in ([], [0])
