"""Defaults of the board contract that most boards share; a board's
backend subclasses :class:`BoardBase` and overrides what differs (a board
may also implement the protocol of :mod:`.contract` from scratch)."""

from __future__ import annotations

import copy
from pathlib import Path

from ..core.errors import BuildError
from ..ir.program import Device, Program
from . import handlers
from .cbuild import defined_symbols
from .contract import BoardCannotRun, Compiled, CompileOptions, Simulator
from .description import BoardDescription
from .resources import by_position


class BoardBase:
    """A board with one target and no simulator, whose devices call the
    board's drivers (``el_drv_<driver>_<handler>(&el_dev<id>)``)."""

    #: A simulation build exists (``--sim``).
    has_simulator = False

    #: Parts of at most this much RAM (bytes) size the debug server's
    #: buffers from the model (model_sized_debug_buffers).
    SMALL_RAM = 2048

    def __init__(self, description: BoardDescription):
        self.description = description
        self.name = description.folder.name
        self.mcu: str | None = None
        self.sim = False
        # A board with parts (board.toml's [mcu.*]) reads them into
        # all_mcus (objects with `ram` and, where the part has one,
        # `eeprom`, in bytes); configure sets `part` to the chosen one.
        self.all_mcus: dict = {}
        self.part = None

    # ---------------------------------------------------------------- configuration

    def mcus(self) -> list[str]:
        """The parts this board builds for (empty: a single target)."""
        return sorted(self.description.table("mcu"))

    def configure(self, mcu: str | None = None, sim: bool = False):
        """A copy for one MCU and build kind (see the contract)."""
        known = self.mcus()
        if mcu is not None and not known:
            raise BuildError(f"board '{self.name}' has no MCU choice (--mcu)")
        chosen = (mcu or self.description.raw.get("default_mcu") or (known[0] if known else "")).lower() or None
        if known and chosen not in known:
            raise BuildError(f"board '{self.name}' has no MCU '{mcu}' (MCUs: {', '.join(known)})")
        if sim and not self.has_simulator:
            raise BuildError(f"board '{self.name}' has no simulator (--sim)")
        board = copy.copy(self)
        board.mcu, board.sim = chosen, bool(sim)
        board.part = self.all_mcus.get(chosen) if chosen is not None else None
        return board

    @property
    def nv_size(self) -> int | None:
        """The EEPROM's bytes: the part's, else board.toml's `nv_size`."""
        if self.part is not None and getattr(self.part, "eeprom", None) is not None:
            return self.part.eeprom
        value = self.description.raw.get("nv_size")
        return int(value) if value is not None else None

    @property
    def debug_slots_on_request(self) -> bool:
        """Whether a debug server gets force and condition slots only where
        the model asks (``debug ... force N conditions N``, docs/protocol.md):
        parts with model-sized debug buffers, and boards whose board.toml
        says `debug_slots_on_request = true`."""
        return self.model_sized_debug_buffers or bool(self.description.raw.get("debug_slots_on_request", False))

    @property
    def model_sized_debug_buffers(self) -> bool:
        """Whether a debug build sizes the server's frame buffers from the
        model (codegen/debug.py: buffer_sizes) instead of the protocol's
        largest frame: parts short of RAM (SMALL_RAM or less), else
        board.toml's `model_sized_debug_buffers`."""
        if self.part is not None:
            return self.part.ram <= self.SMALL_RAM
        return bool(self.description.raw.get("model_sized_debug_buffers", False))

    @property
    def service_api(self) -> bool:
        """Whether the board's own code reads and writes service items
        through el_service_* (board.toml `service_api`, e.g. an HMI): then
        the service map is linked for every model with service items, not
        only for those that serve it over Modbus or persist params."""
        return bool(self.description.raw.get("service_api", False))

    def check_link_baud(self, baud: int) -> None:
        """A remote-execution proxy's link at ``baud`` (``easylab proxy
        --baud``), checked before anything is generated or compiled: a
        BuildError when the board's link cannot run at that rate. Any rate
        here (a board whose divisors come within its C, or whose link is
        no serial port)."""

    # ---------------------------------------------------------------- code

    def device_call(self, device: Device, handler: str) -> str:
        """The handler of the device's type from the model's folder for this
        board (easylab.board.handlers), else the board's driver."""
        model = handlers.call(device, handler, self.name)
        if model is not None:
            return model
        return f"el_drv_{device.driver}_{handler}(&el_dev{device.id});"

    def check(self, program: Program) -> object:
        """Every device whose type brings handler files has one for this
        board, and every such file can be read."""
        problems = [p for p in (handlers.lacking(d, self.name) for d in program.devices) if p]
        if problems:
            raise BuildError(f"the model does not fit the {self.name} board:\n" + "\n".join(by_position(problems)))
        handlers.check_files(program, self.name)
        return None

    def produce(self, program: Program, checked: object, release: bool) -> dict[str, str]:
        """The handlers of the devices whose types bring a file for this
        board (el_handlers.c)."""
        return handlers.source(program, self.name)

    def compile(self, program: Program, checked: object, out_dir: Path, generated: list[Path],
                options: CompileOptions) -> Compiled:
        raise BuildError(f"board '{self.name}' does not compile")

    # ---------------------------------------------------------------- running, flashing

    def build_simulator(self, program: Program, checked: object, out_dir: Path, compiled: Compiled) -> Simulator:
        raise BoardCannotRun(f"board '{self.name}' has no simulator")

    def simulator_command(self, out_dir: Path, program: Program) -> list[str]:
        raise BoardCannotRun(f"board '{self.name}' has no simulator")

    def flash_command(self, out_dir: Path, program: Program, port: str, programmer: str | None = None,
                      baud: int | None = None) -> list[str]:
        raise BuildError(f"board '{self.name}' is not flashed: its program runs where it is built")

    def run_port_program(self, source: Path, work_dir: Path) -> str:
        raise BoardCannotRun(f"board '{self.name}' cannot run programs on this machine")

    def symbols(self, compiled: Compiled) -> set[str]:
        chain = self.description.toolchain
        return defined_symbols(chain.tool("nm", "nm"), compiled.executable, chain.debian_package)
