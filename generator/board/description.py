"""A board's description: its folder's ``board.toml`` (docs/boards.md)."""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from ..core.errors import BuildError


class BoardError(BuildError):
    """A board that cannot be found, or whose folder is broken."""


@dataclass(frozen=True)
class Toolchain:
    """``[toolchain]``: the board's C compiler and its flags."""

    cc: str
    cflags: tuple[str, ...] = ()
    ldflags: tuple[str, ...] = ()
    debian_package: str | None = None  # named when the compiler is missing
    tools: dict = field(default_factory=dict)  # further tools by role (objcopy, size, nm, ...)
    # Options for some files only, after cflags, by file name (the C file's
    # name without its folder): [toolchain.file_cflags].
    file_cflags: dict = field(default_factory=dict)

    def tool(self, role: str, default: str) -> str:
        return str(self.tools.get(role, default))


@dataclass(frozen=True)
class BoardDescription:
    """What board.toml says, with the folder it came from. ``raw`` keeps
    every table for the board's own backend (MCUs, resources, drivers)."""

    name: str
    folder: Path
    title: str
    backend: str  # "FILE.py:ClassName", relative to the folder
    sources: tuple[str, ...]  # the port's C files, relative to the folder
    include_dirs: tuple[str, ...]
    toolchain: Toolchain
    raw: dict

    @property
    def source_paths(self) -> list[Path]:
        return [self.folder / s for s in self.sources]

    @property
    def include_paths(self) -> list[Path]:
        return [self.folder / d for d in self.include_dirs]

    def table(self, key: str) -> dict:
        """A table of board.toml (``{}`` when absent)."""
        value = self.raw.get(key, {})
        return value if isinstance(value, dict) else {}


def read_description(folder: Path) -> BoardDescription:
    """Read ``folder/board.toml``; BoardError names the file and what is
    wrong with it."""
    path = folder / "board.toml"
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as err:
        raise BoardError(f"{path}: cannot read the board description: {err.strerror or err}") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as err:
        raise BoardError(f"{path}: broken board description: {err}") from None
    try:
        chain = data["toolchain"]
        tools = {k: v for k, v in chain.items()
                 if k not in ("cc", "cflags", "ldflags", "debian_package", "file_cflags")}
        file_cflags = {str(name): tuple(str(f) for f in flags) for name, flags in chain.get("file_cflags", {}).items()}
        toolchain = Toolchain(str(chain["cc"]), tuple(chain.get("cflags", [])), tuple(chain.get("ldflags", [])),
                              chain.get("debian_package"), tools, file_cflags)
        backend = str(data["backend"])
        if ":" not in backend:
            raise ValueError(f"backend = \"{backend}\" must name a file and a class, as in \"backend.py:MyBoard\"")
        return BoardDescription(name=str(data.get("name", folder.name)), folder=folder,
                                title=str(data.get("description", "")), backend=backend,
                                sources=tuple(data.get("sources", [])),
                                include_dirs=tuple(data.get("include_dirs", ["."])), toolchain=toolchain, raw=data)
    except KeyError as err:
        raise BoardError(f"{path}: broken board description: the key {err} is missing") from None
    except (TypeError, ValueError) as err:
        raise BoardError(f"{path}: broken board description: {err}") from None
