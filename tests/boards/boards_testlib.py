"""The boards the conformance suite runs on: every board found, and one
board that lives outside the installation, in a temporary folder named by
EASYLAB_BOARD_PATH, as a user's own board would."""

from __future__ import annotations

import atexit
import os
import shutil
import tempfile
from pathlib import Path

from firmware_builds import ROOT, board_conformance

HERE = Path(__file__).resolve().parent
CONTRACT = HERE / "port_contract.c"
USER_BOARD = "userboard"


def _make_user_board() -> Path:
    """A copy of the host board's folder as the board 'userboard', in a
    temporary folder: its backend is split into two modules that import
    each other relatively, and it is found only through
    EASYLAB_BOARD_PATH."""
    base = Path(tempfile.mkdtemp(prefix="easylab-boards-"))
    atexit.register(shutil.rmtree, base, True)
    folder = base / USER_BOARD
    shutil.copytree(ROOT / "boards" / "host", folder, ignore=shutil.ignore_patterns("__pycache__"))
    toml = folder / "board.toml"
    toml.write_text(toml.read_text().replace('name = "host"', f'name = "{USER_BOARD}"')
                    .replace('backend = "backend.py:HostBoard"', 'backend = "user_backend.py:UserBoard"'))
    (folder / "user_naming.py").write_text('TITLE = "a board of its own, outside the installation"\n')
    (folder / "user_backend.py").write_text(
        '"""A user\'s board: the host port under another name."""\n'
        "from .backend import HostBoard\n"
        "from .user_naming import TITLE\n\n\n"
        "class UserBoard(HostBoard):\n"
        "    def compile(self, program, checked, out_dir, generated, options):\n"
        "        compiled = super().compile(program, checked, out_dir, generated, options)\n"
        "        compiled.notes.append(TITLE)\n"
        "        return compiled\n")
    return base


USER_BOARD_PATH = _make_user_board()
# The environment of every command the suite runs: the user's board is
# found through EASYLAB_BOARD_PATH, as a user would set it.
ENV = {"EASYLAB_BOARD_PATH": os.pathsep.join(p for p in (os.environ.get("EASYLAB_BOARD_PATH", ""),
                                                          str(USER_BOARD_PATH)) if p)}
BOARD_PATH = [str(USER_BOARD_PATH)]  # the same for calls in this process


def board_names() -> list[str]:
    from easylab.board.registry import available

    return available(BOARD_PATH)


def conformance(board: str) -> dict:
    """board.toml's [conformance] table of a board."""
    return board_conformance(board, BOARD_PATH)[1]


def conformance_mcu(board: str) -> list[str]:
    """``--mcu M`` for the suite's example builds on a board (none: its default)."""
    mcu = conformance(board).get("mcu")
    return ["--mcu", mcu] if mcu else []


def conformance_model(board: str) -> Path:
    """The model of the suite's own builds (sizes, release builds): board.toml's
    [conformance] `model`, relative to the board's folder, for a board whose
    pins examples/blink.elab does not name; else examples/blink.elab."""
    from easylab.board.registry import board_folders

    model = conformance(board).get("model")
    return board_folders(BOARD_PATH)[board].folder / model if model else ROOT / "examples" / "blink.elab"
