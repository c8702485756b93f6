"""The board contract: what every board implements (docs/boards.md,
"Adding a board").

A board is one folder: ``board.toml`` (its description), the port of the C
runtime (``runtime_c/el_port.h``), its device drivers and its Python
backend, a module of the folder named in board.toml (``backend =
"backend.py:ClassName"``) whose class implements :class:`Board`. The
generator knows boards only through this protocol: it asks a board how to
call a device's handlers, to check the model's resource claims, to add its
own generated files, to compile, to build a simulator and to say how to
flash. Helpers that several boards share (a board.toml's resource tables,
a gcc-style compile, the simulators' tables) are in this package; a board
uses them or not.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol, runtime_checkable

from ..ir.program import Device, Program
from .description import BoardDescription


@dataclass(frozen=True)
class CompileOptions:
    """What ``easylab build`` asks of a compile."""

    release: bool = False  # no debug interface: none of its code is compiled
    extra_cflags: tuple[str, ...] = ()  # --cflags
    cc: str | None = None  # --cc: another C compiler than the board's
    schedule: str | None = None  # --schedule, for the hints of a program that does not fit
    check: bool = False  # --check: the board's further checks of the C (a board without any has nothing to add)
    threads: bool = False  # a multi-core build (docs/multicore.md): only a board that runs threads gets one
    profile: bool = False  # a profiling build: every actor firing timed (host board; docs/multicore.md)


@dataclass
class SizeReport:
    """Memory use of a build against what the part has (bytes). ``None``
    for a limit means the board sets none (a host process)."""

    flash: int
    ram: int
    flash_max: int | None
    ram_max: int | None
    lines: list[str]  # what the build prints about it, one line each


@dataclass
class Compiled:
    """The outcome of :meth:`Board.compile`."""

    executable: Path  # what the build's last line names: a program, an ELF, a .hex, a project folder
    sources: list[Path]  # every C file compiled into it
    size: SizeReport | None = None
    notes: list[str] = field(default_factory=list)  # printed before the last line
    image: Path | None = None  # what a programmer burns (a .hex), when the board is flashed


@dataclass
class Simulator:
    """A program that runs a build with the host board's run options
    (``--fast``, ``--duration``, ``--stimulus``, ``--trace``, ...:
    boards/host/README.md) and writes the same trace files."""

    program: Path
    notes: list[str] = field(default_factory=list)  # what the simulation cannot show


class BoardCannotRun(Exception):
    """This machine cannot run a board's programs (no simulator for it); the
    message says why and what is checked instead."""


@runtime_checkable
class Board(Protocol):
    """The board contract. One instance stands for one configuration of
    the board: the MCU chosen (``configure``) and whether it is a
    simulation build."""

    name: str  # the folder's name, as given to --board
    description: BoardDescription  # board.toml and the folder
    mcu: str | None  # the part chosen; None for a board with a single target
    sim: bool  # a simulation build (the firmware reports its instants to a simulator)

    def configure(self, mcu: str | None = None, sim: bool = False) -> Board:
        """The board for one MCU (``None``: the board's default) and build
        kind; raises BuildError for an MCU the board lacks or a simulation
        build it cannot make."""
        ...

    @property
    def nv_size(self) -> int | None:
        """Bytes of non-volatile storage behind ``el_port_nv_read/write``
        (the persist layer's store), or None when the board has none."""
        ...

    def device_call(self, device: Device, handler: str) -> str:
        """The C statement that runs one handler (open, start, read, write,
        stop, close) of a device in the generated model.c."""
        ...

    def check(self, program: Program) -> object:
        """Check every resource claim and device of the program against the
        board; raise BuildError listing all problems, each at its source
        line. Returns what :meth:`produce` and :meth:`compile` need."""
        ...

    def produce(self, program: Program, checked: object, release: bool) -> dict[str, str]:
        """The board's own generated files (device tables, configuration
        headers, hardware maps): {file name: text}."""
        ...

    def compile(self, program: Program, checked: object, out_dir: Path, generated: list[Path],
                options: CompileOptions) -> Compiled:
        """Compile the generated files with the runtime and the port; check
        that the result fits the part; raise BuildError otherwise."""
        ...

    def build_simulator(self, program: Program, checked: object, out_dir: Path, compiled: Compiled) -> Simulator:
        """The simulator of a simulation build (``--sim``); raise
        BoardCannotRun when the board has none here."""
        ...

    def simulator_command(self, out_dir: Path, program: Program) -> list[str]:
        """The command that runs the simulation build in ``out_dir`` for a
        person: its serial links on pseudo-terminals in ``out_dir``."""
        ...

    def flash_command(self, out_dir: Path, program: Program, port: str, programmer: str | None = None,
                      baud: int | None = None) -> list[str]:
        """The exact command that burns the build in ``out_dir`` into a board
        on ``port``; raise BuildError when the board is not flashed (a host
        process)."""
        ...

    def run_port_program(self, source: Path, work_dir: Path) -> str:
        """Build a C program against the port alone (no model: the port
        contract program, tests/boards/port_contract.c) and run it here;
        return what it printed on its console (stdout, or UART 0). Raise
        BoardCannotRun when no simulator can run it."""
        ...

    def symbols(self, compiled: Compiled) -> set[str]:
        """The names of the functions and objects linked into a build (to
        show, for example, that a release build has no debug code)."""
        ...
