"""Package layout of the `easylab` distribution (the metadata is in
pyproject.toml).

The tree keeps the layout of docs/architecture.md: the compiler lives in
generator/, the C runtime, templates, boards and host tools beside it. They
are installed as one import package, `easylab`, each folder a subpackage
whose files (C sources, templates, board descriptions) go with it, so a
wheel carries everything and a new folder (a board) needs no entry here.
"""

from pathlib import Path

from setuptools import setup

HERE = Path(__file__).resolve().parent
ROOTS = {
    "easylab": "generator",
    "easylab.templates": "templates",
    "easylab.runtime_c": "runtime_c",
    "easylab.boards": "boards",
    "easylab.host_tools": "host_tools",
    "easylab.sim": "sim",
}
SKIPPED = {"__pycache__"}


def packages() -> list[str]:
    """Every folder under the roots, as a dotted package name."""
    names = []
    for package, root in ROOTS.items():
        base = HERE / root
        for folder in sorted([base, *(p for p in base.rglob("*") if p.is_dir())]):
            rel = folder.relative_to(base).parts
            if SKIPPED.intersection(rel):
                continue
            names.append(".".join((package, *rel)))
    return names


PACKAGES = packages()

setup(
    packages=PACKAGES,
    package_dir=ROOTS,
    package_data={name: ["*"] for name in PACKAGES},
    exclude_package_data={name: ["*.pyc"] for name in PACKAGES},
)
