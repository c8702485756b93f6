"""Finding boards: the installation's ``boards/`` and the folders a user
names (``EASYLAB_BOARD_PATH``, ``--board-path``), so that a board for one's
own controller lives in one's own repository (docs/boards.md).

A board folder is found by its ``board.toml``; its backend module is
loaded from the folder as a package of its own (``easylab_board_NAME``),
so the backend may be split into several modules importing each other
relatively, and may import ``easylab`` (the contract and its helpers).
"""

from __future__ import annotations

import importlib
import importlib.machinery
import importlib.util
import os
import sys
from dataclasses import dataclass
from pathlib import Path

from ..core.paths import installed_boards_dir
from .contract import Board
from .description import BoardError, read_description

ENV_VARIABLE = "EASYLAB_BOARD_PATH"


@dataclass(frozen=True)
class BoardFolder:
    name: str
    folder: Path
    installed: bool


def search_path(extra: list[str] | tuple[str, ...] = ()) -> list[Path]:
    """The folders searched for boards, first match wins: ``--board-path``
    folders, then ``EASYLAB_BOARD_PATH`` (``os.pathsep``-separated), then
    the installation's boards. A user's board may thus stand in for an
    installed one of the same name."""
    folders = [Path(p) for p in extra if p]
    folders += [Path(p) for p in os.environ.get(ENV_VARIABLE, "").split(os.pathsep) if p]
    folders.append(installed_boards_dir())
    return folders


def board_folders(extra: list[str] | tuple[str, ...] = ()) -> dict[str, BoardFolder]:
    """Every board found, by name (the first folder of the search path
    that has it)."""
    installed = installed_boards_dir().resolve()
    found: dict[str, BoardFolder] = {}
    for base in search_path(extra):
        if not base.is_dir():
            continue
        for toml in sorted(base.glob("*/board.toml")):
            name = toml.parent.name
            if name not in found:
                found[name] = BoardFolder(name, toml.parent.resolve(), base.resolve() == installed)
    return found


def available(extra: list[str] | tuple[str, ...] = ()) -> list[str]:
    """The names of the boards found."""
    return sorted(board_folders(extra))


def load_board(name: str, extra: list[str] | tuple[str, ...] = ()) -> Board:
    """The board called ``name``, unconfigured (its default MCU). Raises
    BoardError when no folder has it or its backend is broken."""
    folders = board_folders(extra)
    where = folders.get(name)
    if where is None:
        missing = [str(p) for p in search_path(extra) if not p.is_dir()]
        hint = f"; missing board folders: {', '.join(missing)}" if missing else ""
        raise BoardError(f"unknown board '{name}' (boards: {', '.join(sorted(folders)) or 'none'}){hint}")
    description = read_description(where.folder)
    cls = _backend_class(name, where.folder, description.backend)
    board = cls(description)
    if not isinstance(board, Board):
        missing = [m for m in ("configure", "device_call", "check", "produce", "compile", "build_simulator",
                               "flash_command", "run_port_program", "symbols", "nv_size")
                   if not hasattr(board, m)]
        raise BoardError(f"{where.folder}: {description.backend} does not implement the board contract "
                         f"(docs/boards.md): it lacks {', '.join(missing) or 'attributes of the contract'}")
    return board


def _backend_class(name: str, folder: Path, backend: str) -> type:
    """Load the backend's class: the folder as package easylab_board_NAME,
    the file as its module."""
    file_name, _, class_name = backend.partition(":")
    path = folder / file_name
    if not path.is_file() or path.suffix != ".py":
        raise BoardError(f"{folder / 'board.toml'}: its backend file {file_name} does not exist")
    _board_package(name, folder)
    return _class_of(path, f"{_package_name(name)}.{path.stem}", class_name)


def _package_name(board: str) -> str:
    return f"easylab_board_{board}"


def _board_package(name: str, folder: Path) -> None:
    """Make ``folder`` the package easylab_board_NAME (unless it is already)."""
    package = _package_name(name)
    loaded = sys.modules.get(package)
    if loaded is None or list(getattr(loaded, "__path__", [])) != [str(folder)]:
        # A fresh package for this folder (another folder of the same name
        # may have been loaded before: drop its modules).
        for key in [k for k in sys.modules if k == package or k.startswith(package + ".")]:
            del sys.modules[key]
        spec = importlib.machinery.ModuleSpec(package, None, is_package=True)
        spec.submodule_search_locations = [str(folder)]
        sys.modules[package] = importlib.util.module_from_spec(spec)


def board_module(name: str, module: str, extra: list[str] | tuple[str, ...] = ()):
    """A module of a board's backend (for tools and tests that use a
    board's own functions): ``board_module("avr", "devices")``."""
    load_board(name, extra)
    return importlib.import_module(f"{_package_name(name)}.{module}")


def _class_of(path: Path, module_name: str, class_name: str) -> type:
    try:
        module = importlib.import_module(module_name)
    except Exception as err:  # a broken backend: say which and why, not a traceback
        raise BoardError(f"{path}: the board's backend cannot be loaded: {type(err).__name__}: {err}") from None
    cls = getattr(module, class_name, None)
    if cls is None:
        raise BoardError(f"{path}: the board's backend has no class {class_name}")
    return cls
