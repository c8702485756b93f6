"""`easylab graph --serve MODEL`: the drawing in a browser page (headless
Chromium), redrawn when the model or a file it imports is saved, a click on
an element showing its file:line; the locations behind the clicks
(graph.element_locations) checked on the examples and on seeded random
models; the command's refusals."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

from textmate import ROOT

sys.path.insert(0, str(ROOT / "tests" / "debug_web"))
sys.path.insert(0, str(ROOT / "tests" / "frontend"))
sys.path.insert(0, str(ROOT / "tests" / "crosscheck"))
from modelgen import generate  # noqa: E402
from onlinelib import Browser, http, wait_for  # noqa: E402
from weblib import PageServer, start_browser  # noqa: E402
from test_graph_ids import EXAMPLES, SEEDS, expected_ids  # noqa: E402

from easylab.frontend.graph import element_locations  # noqa: E402
from easylab.pipeline import check_file  # noqa: E402

MODEL = ROOT / "examples" / "pneumatic_cylinder.elab"


def _line_of(text: str, pattern: str) -> int:
    return next(i for i, line in enumerate(text.split("\n"), 1) if re.search(pattern, line))


# ---------------------------------------------------------------- locations


def _checked(tmp_path):
    for name in EXAMPLES:
        path = ROOT / "examples" / f"{name}.elab"
        yield name, check_file(path).model, {str(path): path.read_text()}
    for seed in SEEDS:
        text = generate(seed, "atmega2560").text
        yield f"seed {seed}", check_file(f"rand{seed}.elab", text=text).model, {f"rand{seed}.elab": text}


def test_every_element_of_the_drawing_has_the_location_of_its_declaration(tmp_path):
    for name, model, texts in _checked(tmp_path):
        assert model is not None, name
        where = element_locations(model)
        missing = expected_ids(model) - set(where)
        assert not missing, f"{name}: elements without a location: {sorted(missing)}"
        for element, span in where.items():
            if span.file not in texts:
                continue  # declared in an import (std)
            line = texts[span.file].split("\n")[span.line - 1]
            # the element's own name (an edge: its source's) is on its line
            last = re.split(r"[:.]", element.split("/")[-1].split("->")[0])[-1]
            if element.startswith("transition:"):
                last = "transition"
            assert last in line, f"{name}: {element} at {span.line}: {line!r}"


# ---------------------------------------------------------------- the server


class GraphServer(PageServer):
    """`easylab graph --serve MODEL --listen 127.0.0.1:0` in a process, started."""

    what = "easylab graph --serve"
    start_timeout = 60.0

    def __init__(self, model: Path, cwd: Path):
        super().__init__([sys.executable, "-m", "easylab", "graph", "--serve", str(model), "--listen", "127.0.0.1:0"],
                         cwd=cwd)
        self.start()


@pytest.fixture(scope="module")
def browser(tmp_path_factory):
    b = start_browser(tmp_path_factory, Browser)
    yield b
    b.quit()


@pytest.fixture
def served(tmp_path):
    """A copy of pneumatic_cylinder split over two files (its data in an
    import), served; the server stopped and checked after the test."""
    text = MODEL.read_text()
    data = "\n".join(line for line in text.split("\n") if line.startswith(("param ", "var ")))
    main = "\n".join(line for line in text.split("\n") if not line.startswith(("param ", "var ")))
    main = main.replace("import std\n", "import std\nimport \"cylinder_data.elab\"\n", 1)
    (tmp_path / "cylinder_data.elab").write_text(data + "\n")
    (tmp_path / "cylinder.elab").write_text(main)
    assert check_file(tmp_path / "cylinder.elab").model is not None, check_file(tmp_path / "cylinder.elab").report()
    server = GraphServer(Path("cylinder.elab"), tmp_path)
    yield server, tmp_path
    server.stop()


def _version(browser) -> int:
    return browser.js("return window.easylabGraph ? window.easylabGraph.version : -1")


def _has(browser, element_id: str) -> bool:
    return bool(browser.js("return !!document.getElementById(arguments[0])", element_id))


def test_the_page_shows_the_drawing_redraws_on_save_and_shows_where_a_click_is(browser, served):
    server, folder = served
    browser.get(server.url)
    wait_for(lambda: _has(browser, "step:Cylinder.Extending"), 20, "the drawing")
    assert _has(browser, "actor:PositionControl.pid") and _has(browser, "param:kp")

    # A click on a step: its file:line
    main = (folder / "cylinder.elab").read_text()
    browser.click("step:Cylinder.Extending")
    expected = f"cylinder.elab:{_line_of(main, r'step Extending')}"
    wait_for(lambda: expected in (browser.text("#where") or ""), 5, f"{expected} shown")
    # ... and on a param declared in the import: that file's line
    data = (folder / "cylinder_data.elab").read_text()
    browser.click("param:kp")
    expected = f"cylinder_data.elab:{_line_of(data, r'param kp')}"
    wait_for(lambda: expected in (browser.text("#where") or ""), 5, f"{expected} shown")

    # Saving the model redraws it: a new step and its transition
    before = _version(browser)
    edited = main.replace("    step Fault {", "    step Parked {\n    }\n    step Fault {", 1)
    edited = edited.replace("    transition Retracting -> Retracted  when end_in",
                            "    transition Retracting -> Retracted  when end_in\n"
                            "    transition Fault -> Parked when not start_cmd", 1)
    (folder / "cylinder.elab").write_text(edited)
    wait_for(lambda: _has(browser, "step:Cylinder.Parked"), 5, "the new step drawn")
    assert _version(browser) > before
    browser.click("step:Cylinder.Parked")
    expected = f"cylinder.elab:{_line_of(edited, r'step Parked')}"
    wait_for(lambda: expected in (browser.text("#where") or ""), 5, f"{expected} shown")

    # Saving an import redraws it too
    (folder / "cylinder_data.elab").write_text(data + "\nvar spare_flag: bool = false\n")
    wait_for(lambda: _has(browser, "var:spare_flag"), 5, "the import's new var drawn")

    # A model with an error: the error shown (file:line:col), the last drawing kept
    (folder / "cylinder.elab").write_text(edited.replace("step Parked {", "step Parked {{", 1))
    wait_for(lambda: "cylinder.elab:" in (browser.text("#error") or ""), 5, "the error shown")
    assert re.search(r"cylinder\.elab:\d+:\d+", browser.text("#error"))
    assert _has(browser, "step:Cylinder.Parked")
    (folder / "cylinder.elab").write_text(main)
    wait_for(lambda: not _has(browser, "step:Cylinder.Parked") and not browser.text("#error"), 5,
             "the fixed model drawn")
    assert not [e for e in browser.driver.get_log("browser") if e.get("level") == "SEVERE"]


def test_the_server_answers_loopback_host_names_only(served):
    server, _ = served
    port = re.search(r":(\d+)/", server.url).group(1)
    assert http("GET", f"http://127.0.0.1:{port}/drawing").status == 200
    assert http("GET", f"http://127.0.0.1:{port}/", headers={"Host": "localhost:" + port}).status == 200
    assert http("GET", f"http://127.0.0.1:{port}/drawing", headers={"Host": "attacker.example"}).status == 403


@pytest.mark.parametrize("args,message", [
    (["--serve", "-o", "x.svg"], "give no -o"),
    (["--listen", "127.0.0.1:0"], "--listen goes with --serve"),
    (["--serve", "--listen", "nowhere"], "expected ADDR:PORT"),
])
def test_the_command_refuses_what_does_not_go_together(args, message):
    proc = subprocess.run([sys.executable, "-m", "easylab", "graph", str(MODEL), *args], capture_output=True,
                          text=True, timeout=60, cwd=ROOT)
    assert proc.returncode != 0 and message in proc.stderr, proc.stderr
