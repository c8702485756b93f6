"""``make demo``: what EasyLab does today, on the shipped example models.

Checks every example, prints the SDF analysis of its dataflows and draws
each model with Graphviz into ``build/demo/``.
"""

from __future__ import annotations

import sys
from pathlib import Path

from .cli import main as easylab


def main() -> int:
    """Run the demo from the project's root folder."""
    examples = sorted(Path("examples").glob("*.elab"))
    if not examples:
        print("demo: run it from the project's root folder (examples/ not found)", file=sys.stderr)
        return 1
    out = Path("build/demo")
    out.mkdir(parents=True, exist_ok=True)
    status = easylab(["check", *map(str, examples)])
    for model in examples:
        print(f"\n=== {model}")
        status |= easylab(["analyze", str(model)])
        status |= easylab(["graph", str(model), "-o", str(out / f"{model.stem}.svg")])
    return status


if __name__ == "__main__":
    sys.exit(main())
