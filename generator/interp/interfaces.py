"""The debug and service interfaces of local execution (docs/local.md,
"Debug and service interfaces").

The interpreter serves the firmware's own servers, not a copy of them: per
program, the generator's debug and service tables and
``templates/interp_interfaces.c.j2`` (the model's items, actor state and
chart slots as C symbols) are compiled with the runtime's debug server,
Modbus slave and persistent parameters and the host board's transports
(``boards/host/host_interp.c`` is the port) into one shared library,
cached like the actor plug-ins. :class:`Interfaces` drives it:

- the actors' state lives in the library (the plug-ins run on it), so the
  debugger reads and writes the very state the actors use;
- the published items are the library's (the interpreter keeps them in
  the library's arrays, :attr:`Interfaces.items`), and the library runs
  only inside the interpreter's calls into it, so a client always sees the
  published values and its writes reach the program at the points the
  firmware applies them; the charts' slots and steps' times are copied in
  before each call;
- the interpreter calls the debugger's hooks where the firmware does
  (instant, task, chart, step, transition, actor, chart end), waits for real time in
  the library (serving the links), and resynchronises its clock after a
  halt;
- a model sent with the debug protocol's LOAD requests is handed to the
  engine, which replaces the program; the links move to the new program's
  library without a client noticing (``el_interp_handover``).
"""

from __future__ import annotations

import ctypes
import hashlib
import itertools
import os
import shutil
import subprocess
import threading
from pathlib import Path

from ..board import handlers
from ..board.registry import load_board
from ..codegen.debug import protocol_constants
from ..codegen.render import render_interfaces
from ..core.paths import runtime_dir
from ..ir.program import Program
from . import values as V
from .plugins import PluginCache, PluginError

# Runtime and host-board sources of the library (the model's files come
# from the generator). Everything else the firmware has (dispatcher,
# stimulus, trace) is the interpreter's.
RUNTIME_SOURCES = ("el_crc16.c", "el_debug.c", "el_debug_cobs.c", "el_modbus.c", "el_service.c", "el_persist.c",
                   "el_arith.c")
BOARD_SOURCES = ("host_interp.c", "host_load.c", "host_serve.c", "host_debug.c", "host_modbus.c", "host_nvram.c",
                 "host_shared.c")
CFLAGS = ["-std=c99", "-O2", "-Wall", "-Wextra", "-Werror", "-pedantic", "-D_POSIX_C_SOURCE=200809L", "-fPIC",
          "-shared", "-DEL_DEBUG=1", "-DEL_DEBUG_BOARD_COMMANDS=1"]
LDFLAGS = ["-Wl,--no-undefined", "-lm"]

# The debug protocol's numbers (probe kinds, LOAD states), from its header.
K = protocol_constants()

# Libraries loaded by this process (see Library._load_fresh).
_LOADED: set[Path] = set()
_LOADED_LOCK = threading.Lock()
_COPIES = itertools.count()


class Library:
    """One program's compiled interfaces library and its generated files
    (debug_map.json, service_map.json, ... in ``directory``)."""

    def __init__(self, program: Program, cache: PluginCache):
        self.program = program
        board = load_board("host")
        files = render_interfaces(program, board)
        runtime, board_dir = runtime_dir(), board.description.folder
        sources = [runtime / n for n in RUNTIME_SOURCES] + [board_dir / n for n in BOARD_SOURCES]
        h = hashlib.sha256()
        for part in ["easylab interfaces library", " ".join(CFLAGS + LDFLAGS), cache.compiler,
                     cache.compiler_identity, *(f"{n}\0{t}" for n, t in sorted(files.items())),
                     *(p.read_text(encoding="utf-8") for p in sorted(runtime.glob("*.h"))),
                     *(p.read_text(encoding="utf-8") for p in sorted(board_dir.glob("*.h"))),
                     *(p.read_text(encoding="utf-8") for p in sources)]:
            h.update(part.encode("utf-8"))
            h.update(b"\0")
        self.directory = cache.directory / f"interfaces-{h.hexdigest()[:32]}"
        self.path = self.directory / "libinterfaces.so"
        if not self.path.is_file():
            self._compile(files, sources, cache.compiler, runtime, board_dir)
        self.lib = self._load_fresh()
        self.files = {name: self.directory / name for name in files}

    def _load_fresh(self) -> ctypes.CDLL:
        """Load the library with its own static storage. A library loaded
        before in this process (the program ran earlier, was replaced, and
        comes back) would be the same copy, with that run's links, state and
        watch table: such a one is loaded from a private copy instead."""
        with _LOADED_LOCK:
            again = self.path in _LOADED
            _LOADED.add(self.path)
        source = self.path
        if again:
            source = self.directory / f"libinterfaces.{os.getpid()}.{next(_COPIES)}.so"
            try:
                shutil.copyfile(self.path, source)
            except OSError as err:
                raise PluginError(f"cannot copy the interfaces library {self.path}: {err.strerror or err}") from None
        try:
            return ctypes.CDLL(str(source))
        except OSError as err:
            raise PluginError(f"cannot load the interfaces library {source}: {err}") from None
        finally:
            if again:
                source.unlink(missing_ok=True)  # loaded: the file is no longer needed

    def _compile(self, files: dict[str, str], sources: list[Path], compiler: str, runtime: Path,
                 board_dir: Path) -> None:
        gen = self.directory
        try:
            gen.mkdir(parents=True, exist_ok=True)
            for name, text in files.items():  # whole files only: another run may be compiling them
                temp = gen / f"{name}.{os.getpid()}.{threading.get_ident()}.tmp"
                temp.write_text(text, encoding="utf-8")
                os.replace(temp, gen / name)
        except OSError as err:
            raise PluginError(f"cannot write to the plug-in cache {gen}: {err.strerror or err}") from None
        temp = gen / f"libinterfaces.{os.getpid()}.{threading.get_ident()}.tmp"
        c_files = [gen / n for n in files if n.endswith(".c")]
        cmd = [compiler, *CFLAGS, f"-I{gen}", f"-I{runtime}", f"-I{board_dir}", "-o", str(temp),
               *map(str, c_files + sources), *LDFLAGS]
        proc = subprocess.run(cmd, capture_output=True, text=True)
        if proc.returncode != 0:
            temp.unlink(missing_ok=True)
            raise PluginError(f"the interfaces library of model '{self.program.name}' does not compile "
                              f"({compiler}, sources in {gen}):\n{(proc.stdout + proc.stderr).rstrip()}")
        os.replace(temp, self.path)


class Interfaces:
    """The running side of one program's library: links, item copies,
    debugger hooks. ``open`` starts the links (adopting those of the
    library it replaces); every other method is for the engine's thread."""

    def __init__(self, library: Library):
        self.library = library
        self.program = library.program
        lib = library.lib
        self._fn(lib.el_interp_open, ctypes.c_bool,
                 [ctypes.c_char_p, ctypes.c_char_p, ctypes.c_char_p, ctypes.c_char_p])
        for name, res, args in (
                ("el_interp_set_tick", None, [ctypes.c_uint64]), ("el_interp_idle", None, [ctypes.c_uint16]),
                ("el_interp_take_resync", ctypes.c_uint8, []), ("el_interp_has_debug", ctypes.c_bool, []),
                ("el_interp_armed", ctypes.c_uint8, []), ("el_interp_instant", None, []),
                ("el_interp_force", None, []), ("el_interp_forcing", ctypes.c_uint8, []),
                ("el_interp_task_begin", None, [ctypes.c_uint8]), ("el_interp_task_end", None, []),
                ("el_interp_probe", None, [ctypes.c_uint8, ctypes.c_uint16, ctypes.c_uint16]),
                ("el_interp_abort_halt", None, []), ("el_interp_handover", ctypes.c_bool, []),
                ("el_interp_close", None, []),
                ("el_interp_take_load", ctypes.c_uint32, [ctypes.POINTER(ctypes.c_void_p)]),
                ("el_interp_load_result", None, [ctypes.c_uint8, ctypes.c_uint32, ctypes.c_char_p])):
            self._fn(getattr(lib, name), res, args)
        self.has_debug = bool(lib.el_interp_has_debug())
        n_items, n_actors = len(self.program.items), len(self.program.instances)
        items = (ctypes.c_void_p * max(1, n_items)).in_dll(lib, "el_interp_items")
        self.items = [(V.ctype(i.type) * i.count).from_address(items[i.id]) for i in self.program.items]
        states = (ctypes.c_void_p * max(1, n_actors)).in_dll(lib, "el_interp_actor_state")
        sizes = (ctypes.c_size_t * max(1, n_actors)).in_dll(lib, "el_interp_actor_state_size")
        self.actor_states = [(states[k], sizes[k]) for k in range(n_actors)]
        slots = (ctypes.c_void_p * max(1, len(self.program.charts))).in_dll(lib, "el_interp_chart_slots")
        self.chart_slots = [(ctypes.c_uint8 * c.slots).from_address(slots[c.id]) for c in self.program.charts]
        times = (ctypes.c_void_p * max(1, len(self.program.charts))).in_dll(lib, "el_interp_step_times")
        self.step_times = [(ctypes.c_uint32 * len(c.steps)).from_address(times[c.id]) for c in self.program.charts]
        fired = (ctypes.c_void_p * max(1, len(self.program.charts))).in_dll(lib, "el_interp_chart_fired")
        self.chart_fired = [(V.ctype(c.fired_type) * 1).from_address(fired[c.id]) for c in self.program.charts]
        # The devices' state the debug tables read (codegen/debug.py): a copy of each device's, refreshed by push.
        self.device_states = {dev.id: (ctypes.c_uint8 * 1).in_dll(lib, f"el_mdev{dev.id}_state")
                              for dev in handlers.state_devices(self.program, "host")} if self.has_debug else {}
        self._armed = lib.el_interp_armed
        self.status = (ctypes.c_uint16 * max(1, len(self.program.status))).in_dll(lib, "el_interp_status")

    @staticmethod
    def _fn(fn, restype, argtypes) -> None:
        fn.restype = restype
        fn.argtypes = argtypes

    # ------------------------------------------------------------ life

    def open(self, debug: str | None, modbus_tcp: str | None, modbus_rtu: str | None, nvram: str | None) -> bool:
        """Open the links (or adopt those handed over) and start the
        interfaces, as the firmware does at boot. False when a link cannot
        be opened (the library has said why on stderr)."""
        # Kept for the library's life: the host board keeps pointers to them (the nvram path).
        self._open_args = tuple(None if a is None else str(a).encode() for a in (debug, modbus_tcp, modbus_rtu, nvram))
        return bool(self.library.lib.el_interp_open(*self._open_args))

    def handover(self) -> bool:
        """Hand the links over to the next program's library."""
        return bool(self.library.lib.el_interp_handover())

    def close(self) -> None:
        self.library.lib.el_interp_close()

    def abort_halt(self) -> None:
        """Let a halted program go, for good (shutting down)."""
        self.library.lib.el_interp_abort_halt()

    # ------------------------------------------------------------ items

    def push(self, published: list, charts, devices=None) -> None:
        """The interpreter's published items, chart slots, steps' times,
        last fired transitions and devices' state (``devices``:
        interp.devices.ModelDevices) into the library (items that are the
        library's own arrays stay as they are)."""
        for array, values in zip(self.items, published):
            if values is not array:
                array[:] = values
        for array, times, fired, runner in zip(self.chart_slots, self.step_times, self.chart_fired, charts):
            array[:] = [0xFF if s is None else s for s in runner.slots]
            times[:] = runner.elapsed
            fired[0] = runner.chart.fired_none if runner.fired is None else runner.fired
        if devices is not None:
            for dev_id, target in self.device_states.items():
                dev = devices.devices.get(dev_id)
                if dev is not None:
                    ctypes.memmove(ctypes.addressof(target), dev.state, dev.plugin.state_size)

    def pull(self, published: list) -> None:
        """What clients wrote (or persistent storage restored) back into the
        interpreter's published items."""
        for k, array in enumerate(self.items):
            if published[k] is array:
                continue
            values = array[:]
            if values != published[k]:
                published[k] = values

    def set_status(self, status_id: int, value: int) -> None:
        """A status item's count (docs/ir.md, "Status items"), as its
        uint16 saturates."""
        self.status[status_id] = min(max(value, 0), 0xFFFF)

    # ------------------------------------------------------------ hooks

    @property
    def armed(self) -> bool:
        """Whether a probe must call into the debug server."""
        return bool(self._armed())

    def set_tick(self, tick: int) -> None:
        self.library.lib.el_interp_set_tick(tick)

    def idle(self, max_ms: int) -> None:
        self.library.lib.el_interp_idle(max_ms)

    def instant(self) -> None:
        self.library.lib.el_interp_instant()

    @property
    def forcing(self) -> bool:
        """Whether anything is forced or a conditional breakpoint set (the
        force point then calls into the server)."""
        return bool(self.library.lib.el_interp_forcing())

    def force(self) -> None:
        """EL_DEBUG_FORCE: the forced elements again, then the conditional
        breakpoints (after the instant's device reads)."""
        self.library.lib.el_interp_force()

    def task_begin(self, task: int) -> None:
        self.library.lib.el_interp_task_begin(task)

    def task_end(self) -> None:
        self.library.lib.el_interp_task_end()

    def probe(self, kind: int, a: int, b: int = 0) -> None:
        self.library.lib.el_interp_probe(kind, a, b)

    def take_resync(self) -> bool:
        return bool(self.library.lib.el_interp_take_resync())

    # ------------------------------------------------------------ model replacement

    def take_load(self) -> bytes | None:
        """A model text a client committed with LOAD_COMMIT, once."""
        where = ctypes.c_void_p()
        size = self.library.lib.el_interp_take_load(ctypes.byref(where))
        return ctypes.string_at(where.value, size) if size else None

    def load_result(self, state: int, program_id: int = 0, message: str = "") -> None:
        """What LOAD_STATUS reports (EL_DBG_LOAD_REFUSED, _REPLACED)."""
        self.library.lib.el_interp_load_result(state, program_id, message.encode("utf-8", "replace"))


PROBE = {name: getattr(K, f"P_{name.upper()}")
         for name in ("instant", "task", "chart", "step", "transition", "actor", "chart_end")}
LOAD_REFUSED, LOAD_REPLACED = K.LOAD_REFUSED, K.LOAD_REPLACED
