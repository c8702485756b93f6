"""Boards: each folder of boards/ describes one (board.toml) and brings its
port and drivers. Adding a board touches nothing outside its folder."""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, field
from pathlib import Path


class BoardError(Exception):
    """A board that does not exist or whose description is broken."""


def _data_dir(name: str) -> Path:
    """A folder installed beside the package (wheel: easylab/NAME) or, in the
    source tree, beside generator/ (see pyproject.toml)."""
    here = Path(__file__).resolve().parent
    for candidate in (here / name, here.parent / name):
        if candidate.is_dir():
            return candidate
    raise BoardError(f"the installation lacks its '{name}' folder (looked beside {here})")


def boards_dir() -> Path:
    return _data_dir("boards")


def runtime_dir() -> Path:
    return _data_dir("runtime_c")


def templates_dir() -> Path:
    return _data_dir("templates")


def available() -> list[str]:
    """The names of the boards this installation has."""
    return sorted(p.parent.name for p in boards_dir().glob("*/board.toml"))


@dataclass
class Board:
    """A board as its board.toml describes it."""

    name: str
    path: Path
    description: str
    simulated_drivers: bool
    sources: list[str]
    include_dirs: list[str]
    cc: str
    cflags: list[str]
    ldflags: list[str]
    debian_package: str | None = None
    raw: dict = field(default_factory=dict)

    def device_call(self, device, handler: str) -> str:
        """The C statement running one handler (open/start/read/write/stop/close)
        of a device."""
        if self.simulated_drivers:
            return f"el_sim_{handler}({device.id}u);"
        return f"el_drv_{device.driver}_{handler}(&el_dev{device.id});"


def load_board(name: str) -> Board:
    """Read boards/NAME/board.toml."""
    path = boards_dir() / name
    toml = path / "board.toml"
    if not toml.is_file():
        known = ", ".join(available()) or "none"
        raise BoardError(f"unknown board '{name}' (boards: {known})")
    try:
        data = tomllib.loads(toml.read_text(encoding="utf-8"))
        chain = data.get("toolchain", {})
        return Board(name=data.get("name", name), path=path, description=data.get("description", ""),
                     simulated_drivers=bool(data.get("simulated_drivers", False)),
                     sources=list(data.get("sources", [])), include_dirs=list(data.get("include_dirs", ["."])),
                     cc=chain["cc"], cflags=list(chain.get("cflags", [])), ldflags=list(chain.get("ldflags", [])),
                     debian_package=chain.get("debian_package"), raw=data)
    except (tomllib.TOMLDecodeError, KeyError, TypeError) as err:
        raise BoardError(f"{toml}: broken board description: {err}") from None
