"""The tree says what the program does (docs/architecture.md): the
package is grouped by stage of the pipeline, no module imports itself back
through others, no module grows past 600 lines, and every stage imports
only the stages before it. The IR is the only contract between the front
end and the backends: no backend imports the front end or the analyses."""

from __future__ import annotations

import ast
import re
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "generator"
MAX_LINES = 600

# The stages in pipeline order; a stage may import the ones before it.
STAGES = ["core", "frontend", "analysis", "ir", "pipeline", "codegen", "board", "build", "interp", "remote", "cli"]
# What each backend may see of the stages before the IR, and why.
ALLOWED = {
    ("ir", "analysis"): "the IR carries the schedule notation of the SDF analysis (ir/program.py re-exports it) "
                        "and lowering reads the analysed model",
    ("ir", "frontend"): "lowering (ir/lower.py) reads the checked model",
}
LOWERING = {"easylab.ir.lower"}  # the one module of the IR stage that reads the front end


def module_name(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(["easylab", *parts])


def modules() -> dict[str, Path]:
    return {module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def imports(name: str, path: Path, known: set[str]) -> set[str]:
    """Every easylab module ``path`` imports, at module level or inside functions."""
    package = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
    found = set()
    tree = ast.parse(path.read_text(encoding="utf-8"))
    # imports for type checkers only are not imports at run time
    typing_only = {id(n) for block in ast.walk(tree) if isinstance(block, ast.If)
                   and isinstance(block.test, ast.Name) and block.test.id == "TYPE_CHECKING"
                   for stmt in block.body for n in ast.walk(stmt)}
    for node in ast.walk(tree):
        if id(node) in typing_only:
            continue
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            elif node.module and node.module.split(".")[0] == "easylab":
                target = node.module
            else:
                continue
            for alias in node.names:
                sub = f"{target}.{alias.name}"
                found.add(sub if sub in known else target)
        elif isinstance(node, ast.Import):
            found.update(a.name for a in node.names if a.name.split(".")[0] == "easylab")
    # importing a.b.c runs a/__init__ and a/b/__init__ too, but those are
    # the packages' own imports, already counted as theirs
    return {m for m in found if m in known and m != name}


def graph() -> dict[str, set[str]]:
    mods = modules()
    known = set(mods)
    return {name: imports(name, path, known) for name, path in mods.items()}


def cycles(g: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (the SDF
    analysis's own Tarjan, on the import graph)."""
    from easylab.analysis.sdf._digraph import strongly_connected_components

    names = sorted(g)
    number = {name: k for k, name in enumerate(names)}
    succ = [sorted(number[t] for t in g[name] if t in number) for name in names]
    return sorted(sorted(names[k] for k in comp)
                  for comp in strongly_connected_components(range(len(names)), succ) if len(comp) > 1)


def stage(module: str) -> str | None:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 and parts[1] in STAGES else None


def test_no_import_cycle_in_the_package():
    assert cycles(graph()) == []


def test_the_cycle_finder_finds_a_cycle():
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_no_module_over_600_lines():
    long = {str(p.relative_to(ROOT)): n for p in PACKAGE.rglob("*.py")
            if (n := len(p.read_text(encoding="utf-8").splitlines())) > MAX_LINES}
    long |= {str(p.relative_to(ROOT)): n for p in (ROOT / "boards").rglob("*.py")
             if (n := len(p.read_text(encoding="utf-8").splitlines())) > MAX_LINES}
    assert long == {}


def test_stages_import_only_the_stages_before_them():
    wrong = []
    for module, targets in graph().items():
        here = stage(module)
        for target in targets:
            there = stage(target)
            if here is None or there is None or here == there:
                continue
            if STAGES.index(there) > STAGES.index(here):
                wrong.append(f"{module} imports {target}: a later stage")
    assert wrong == []


def test_backends_see_the_ir_not_the_front_end():
    backends = {"codegen", "board", "build", "interp"}
    wrong = []
    for module, targets in graph().items():
        here = stage(module)
        for target in targets:
            there = stage(target)
            if here in backends and there in ("frontend", "analysis"):
                wrong.append(f"{module} imports {target}")
            if here == "ir" and there in ("frontend", "analysis") and module not in LOWERING \
                    and target != "easylab.analysis.sdf.schedule":
                wrong.append(f"{module} imports {target}")
    assert wrong == []


def test_no_board_names_in_the_generator():
    """A board is a folder of boards/: the generator names none of them
    (comments and docstrings may, as examples)."""
    names = {p.parent.name for p in (ROOT / "boards").glob("*/board.toml")} - {"host"}
    wrong = []
    for path in PACKAGE.rglob("*.py"):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        docstrings = {id(n.body[0].value) for n in ast.walk(tree)
                      if isinstance(n, (ast.Module, ast.ClassDef, ast.FunctionDef)) and n.body
                      and isinstance(n.body[0], ast.Expr) and isinstance(n.body[0].value, ast.Constant)}
        for node in ast.walk(tree):
            if isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docstrings:
                for name in names:
                    if re.search(rf"\b{name}\b", node.value, re.IGNORECASE):
                        wrong.append(f"{path.relative_to(ROOT)}:{node.lineno}: {node.value[:60]!r}")
    assert wrong == []


def test_the_architecture_document_shows_every_stage():
    text = (ROOT / "docs" / "architecture.md").read_text(encoding="utf-8")
    for name in STAGES:
        folder = PACKAGE / name
        shown = f"generator/{name}/" if folder.is_dir() else f"generator/{name}.py"
        assert shown in text, f"docs/architecture.md does not show {shown}"


def test_commands_start_without_the_packages_of_other_commands():
    """`easylab check` and `easylab build` import neither the language
    server's packages nor the web servers' (each costs a fresh process
    most of a second; the suite starts thousands)."""
    import subprocess
    import sys

    heavy = ("pygls", "lsprotocol", "aiohttp", "selenium", "easylab.lsp")
    probe = ("import sys, contextlib, io\n"
             "from easylab.cli import main\n"
             "with contextlib.redirect_stdout(io.StringIO()):\n"
             "    main(sys.argv[1:])\n"
             f"print(sorted(m for m in sys.modules if m.split('.')[0] in {heavy!r} or m.startswith('easylab.lsp')))\n")
    for args in (["check", str(ROOT / "examples" / "blink.elab")], ["boards"]):
        proc = subprocess.run([sys.executable, "-c", probe, *args], capture_output=True, text=True, timeout=120)
        assert proc.returncode == 0, proc.stderr
        assert proc.stdout.strip().splitlines()[-1] == "[]", (args, proc.stdout)
