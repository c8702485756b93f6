"""Where the installation keeps the parts that are not Python: the C
runtime, the templates of generated C and the installed boards.

In a wheel they are subpackages of ``easylab`` (``easylab/runtime_c``, ...);
in the source tree they sit beside ``generator/`` (see setup.py).
"""

from __future__ import annotations

from pathlib import Path

PACKAGE_DIR = Path(__file__).resolve().parents[1]


class InstallationError(Exception):
    """A folder of the installation is missing (a broken install)."""


def data_dir(name: str) -> Path:
    """The installed folder ``name`` (wheel: easylab/NAME; source tree: NAME
    beside generator/)."""
    for candidate in (PACKAGE_DIR / name, PACKAGE_DIR.parent / name):
        if candidate.is_dir():
            return candidate
    raise InstallationError(f"the installation lacks its '{name}' folder (looked beside {PACKAGE_DIR})")


def runtime_dir() -> Path:
    """runtime_c/: the portable C runtime every board compiles."""
    return data_dir("runtime_c")


def sim_dir() -> Path:
    """sim/: what the boards' simulator harnesses share (their core, the
    chip-model API and its dispatch, the std chip models)."""
    return data_dir("sim")


def templates_dir() -> Path:
    """templates/: the Jinja2 templates of the generated C."""
    return data_dir("templates")


def installed_boards_dir() -> Path:
    """boards/: the boards that come with the installation."""
    return data_dir("boards")
