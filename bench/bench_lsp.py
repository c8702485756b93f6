"""Language server benchmark: diagnostics after an edit (docs/editors.md).

For every example, and for the front-end benchmark's generated model
(bench_frontend.py, 5,000 actor instances), the file is opened in the
server's workspace once, then edited inside one declaration; the time is
that of the server's re-check after the edit (the chunked parser re-parses
the edited declaration only, the SDF analysis runs for the dataflows whose
graph changed only, the checker runs on the whole model) up to the
diagnostics it would publish. The large model is also timed after edits
that change one dataflow's graph (so that this dataflow's SDF analysis
runs again). Goals: 100 ms per example, 1.5 s for the 5,000-actor model.
Run: python bench/bench_lsp.py [out_dir] [actors]
"""

from __future__ import annotations

import json
import re
import statistics
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
REPEATS = 5


def _edit(text: str, n: int) -> str:
    """A small edit inside the last declaration: a comment changed."""
    return text.rstrip("\n") + f"  // edit {n}\n"


def _graph_edit(text: str, n: int) -> str:
    """An edit that changes one dataflow's graph: the first actor instance
    of the last dataflow renamed (declaration and edges)."""
    start = text.rindex("\ndataflow ")
    end = text.index("\n}", start)
    return text[:start] + re.sub(r"\ba0\b", f"first{n}", text[start:end]) + text[end:]


def time_edits(path: Path, text: str, repeats: int = REPEATS, edit=_edit) -> dict:
    """Median and worst seconds from an edit to its diagnostics, and how
    many dataflows the edits had analysed again."""
    from easylab.lsp.workspace import Workspace

    workspace = Workspace()
    start = time.perf_counter()
    errors = len(workspace.open(path, text).result.diagnostics.sorted())
    opened = time.perf_counter() - start
    times = []
    analysed = workspace.sdf_cache.analyses
    for n in range(repeats):
        edited = edit(text, n)
        start = time.perf_counter()
        # as the server does: the analysis is published, then only the workspace keeps it
        workspace.open(path, edited).diagnostics_by_file()
        times.append(time.perf_counter() - start)
    return {"open_s": round(opened, 4), "edit_median_s": round(statistics.median(times), 4),
            "edit_max_s": round(max(times), 4), "errors": errors,
            "dataflows_reanalysed": workspace.sdf_cache.analyses - analysed}


def run(actors: int = 5000) -> dict:
    sys.path.insert(0, str(HERE))
    from bench_frontend import generate_model
    from easylab.frontend.parser import _ast_parser

    _ast_parser()  # grammar tables: built once per process
    examples = {}
    for path in sorted((ROOT / "examples").rglob("*.elab")):
        if not path.name.startswith("."):
            examples[str(path.relative_to(ROOT))] = time_edits(path, path.read_text(encoding="utf-8"))
    with tempfile.TemporaryDirectory() as tmp:
        big = Path(tmp) / "big.elab"
        text = generate_model(actors)
        big.write_text(text)
        generated = time_edits(big, text, repeats=3)
        dataflow_edit = time_edits(big, text, repeats=3, edit=_graph_edit)
    generated["actors"] = actors
    generated["graph_edit_median_s"] = dataflow_edit["edit_median_s"]
    generated["graph_edit_max_s"] = dataflow_edit["edit_max_s"]
    generated["graph_edit_dataflows_reanalysed"] = dataflow_edit["dataflows_reanalysed"]
    return {"examples": examples, "generated": generated,
            "worst_example_edit_s": max(e["edit_max_s"] for e in examples.values())}


def main(out_dir: Path, tiny: bool = False, actors: int = 5000) -> dict:
    figures = run(100 if tiny else actors)
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / "lsp.json").write_text(json.dumps(figures, indent=2) + "\n")
    for name, f in figures["examples"].items():
        print(f"{name}: diagnostics after an edit {f['edit_median_s'] * 1000:.1f} ms "
              f"(worst {f['edit_max_s'] * 1000:.1f} ms; open {f['open_s'] * 1000:.1f} ms)")
    g = figures["generated"]
    print(f"generated model, {g['actors']} actors: open {g['open_s']} s, diagnostics after an edit "
          f"{g['edit_median_s']} s (worst {g['edit_max_s']} s); after an edit of one dataflow's graph "
          f"{g['graph_edit_median_s']} s (worst {g['graph_edit_max_s']} s; dataflows re-analysed: "
          f"{g['graph_edit_dataflows_reanalysed']} for 3 edits)")
    return figures


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "bench/results"),
         actors=int(sys.argv[2]) if len(sys.argv) > 2 else 5000)
