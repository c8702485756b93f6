"""Acceptance: the CD-to-DAT benchmark, built in Python and read from SDF3."""

from pathlib import Path

import pytest

from easylab.analysis.sdf import analyze, load_sdf3, repetition_vector, verify
from sdf_testlib import cd2dat, simulate

DATA = Path(__file__).parent / "data"

EXPECTED = {
    # (flat SAS, best SAS, SAS lower bound, min-buffer, per-edge bound)
    False: (1021, 264, 82, 32, 32),
    True: (1181, 424, 242, 192, 192),
}


def graphs():
    yield "python", cd2dat(), False
    yield "python+G", cd2dat(with_g=True), True
    yield "sdf3", load_sdf3(DATA / "cd2dat.xml"), False
    yield "sdf3-text", load_sdf3((DATA / "cd2dat.xml").read_text()), False


@pytest.mark.parametrize("label, graph, with_g", list(graphs()), ids=[g[0] for g in graphs()])
def test_cd2dat_figures(label, graph, with_g):
    expected_reps = {"A": 147, "B": 147, "C": 98, "D": 28, "E": 32, "F": 160}
    if with_g:
        expected_reps["G"] = 1
    assert repetition_vector(graph) == expected_reps

    flat_total, sas_total, sas_bound, min_total, edge_bound = EXPECTED[with_g]
    sas = analyze(graph, "sas")
    assert sas.repetitions == expected_reps
    assert list(sas.repetitions) == list(expected_reps)
    assert sas.flat_sas_total == flat_total
    assert sas.buffer_total == sas_total
    assert sas.sas_lower_bound == sas_bound
    assert sas.edge_lower_bound == edge_bound
    assert sas.single_appearance and sas.schedule.is_single_appearance

    best = analyze(graph, "min-buffer")
    assert best.buffer_total == min_total
    assert best.optimal

    flat = analyze(graph, "flat")  # every actor's firings in one run, in topological order
    assert flat.buffer_total == flat_total and flat.single_appearance
    assert [(f.actor, f.count) for f in flat.schedule.body] == list(expected_reps.items())

    for analysis in (sas, best, flat):
        sizes = verify(graph, analysis.schedule)
        peaks = simulate(graph, analysis.firings(), expected_reps)
        assert dict(analysis.buffers) == sizes == peaks
        assert sum(sizes.values()) == analysis.buffer_total


def test_cd2dat_seventh_actor_adds_160_everywhere():
    plain, extended = cd2dat(), cd2dat(with_g=True)
    for kind in ("sas", "flat", "min-buffer"):
        a, b = analyze(plain, kind), analyze(extended, kind)
        assert b.buffer_total - a.buffer_total == 160
        assert b.sas_lower_bound - a.sas_lower_bound == 160
        assert b.edge_lower_bound - a.edge_lower_bound == 160
        assert b.flat_sas_total - a.flat_sas_total == 160


def test_cd2dat_sdf3_matches_python_graph():
    imported = load_sdf3(DATA / "cd2dat.xml")
    built = cd2dat()
    assert imported.name == "cd2dat"
    assert imported.actors == built.actors
    assert [(e.src, e.dst, e.prod, e.cons, e.delay) for e in imported.edges] == [
        (e.src, e.dst, e.prod, e.cons, e.delay) for e in built.edges
    ]
    first = imported.edges[0]
    assert first.label == "ab (A -> B)"
    assert str(first.loc).endswith("cd2dat.xml:31")


def test_cd2dat_json_and_text_report():
    analysis = analyze(cd2dat(), "sas")
    data = analysis.to_json_dict("cd2dat")
    assert set(data) == {
        "name", "repetitions", "schedule", "buffers", "buffer_total",
        "sas_lower_bound", "edge_lower_bound",
    }
    assert data["name"] == "cd2dat"
    assert data["repetitions"] == {"A": 147, "B": 147, "C": 98, "D": 28, "E": 32, "F": 160}
    assert data["schedule"] == analysis.schedule_text
    assert [(b["src"], b["dst"]) for b in data["buffers"]] == [
        ("A", "B"), ("B", "C"), ("C", "D"), ("D", "E"), ("E", "F"),
    ]
    assert sum(b["size"] for b in data["buffers"]) == data["buffer_total"] == 264
    assert (data["sas_lower_bound"], data["edge_lower_bound"]) == (82, 32)
    text = analysis.render_text("cd2dat")
    assert "cd2dat" in text and "264" in text and "B -> C" in text
