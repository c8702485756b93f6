"""The interpreter of the IR: LET dispatcher, tasks, channels, devices, and
live replacement of the model (docs/local.md).

:class:`ProgramState` is everything one program holds at run time (the
published items, each task's local copies, channels, actor instances,
dataflows and charts); :class:`Engine` walks the program's dispatch table
(docs/ir.md, "Tasks and logical execution time") and can swap in a new
program between two instants (:meth:`Engine.replace_model`), carrying the
state of whatever did not change.
"""

from __future__ import annotations

import os
import queue
import shutil
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from ..ir.program import Program
from .clock import Clock
from .devices import ModelDevices
from .interfaces import LOAD_REFUSED, LOAD_REPLACED, Interfaces, Library
from .plugins import PluginCache, PluginError
from .replacement import CarriedPublication, Replacement, carry, transfer
from .state import InstantPlan, ProgramState
from .stimulus import Stimulus
from .trace import Sampler, TraceWriter, columns_of


# A stretch of instants in the runner alone ends after this many instants or
# operations (a few milliseconds): signals, replacements and other threads
# are then attended to.
NATIVE_INSTANTS = 100_000
NATIVE_OPS = 1_000_000
NEVER_US = 2 ** 64 - 1


# ====================================================================== the engine


@dataclass
class InterfaceOptions:
    """What the interpreter serves (the host board's options): ``debug``
    ``pty:LINK`` or ``tcp:PORT`` (``,halt`` to start halted), ``modbus_tcp``
    a port, ``modbus_rtu`` ``pty:LINK``, ``nvram`` the file of persistent
    params (None: in memory); ``maps`` a folder for debug_map.json and
    service_map.* (rewritten at each replacement); ``model`` and
    ``schedule`` read a model sent over the debug link (its imports are
    relative to ``model``)."""

    debug: str | None = None
    modbus_tcp: str | None = None
    modbus_rtu: str | None = None
    nvram: str | None = None
    maps: Path | None = None
    model: Path | None = None
    schedule: str | None = None


class InterfaceError(Exception):
    """A link of the interfaces that cannot be opened (the library printed
    why on stderr)."""


class Engine:
    """Runs a program: boot, the dispatch table instant after instant,
    shutdown; and live replacement (:meth:`replace_model`).

    ``stimulus`` feeds device data (and, if it has such columns, params and
    vars); ``trace`` records every instant. ``on_replace`` is called with a
    :class:`Replacement` after every swap. With ``interfaces`` each program
    runs with its interfaces library (interfaces.py): the debug and service
    interfaces are served, and a model sent over the debug link replaces
    the program; ``say`` prints what the run reports (a refused model).
    ``cores`` > 1 runs the parallel parts of the IR's multi-core plan on
    that many threads where the plan says it pays (``always_parallel``:
    wherever it can), the program and every replacement
    (docs/multicore.md)."""

    command = "run"  # the easylab command running it, in what it says

    def __init__(self, program: Program, plugin_cache: PluginCache | None = None,
                 stimulus: Stimulus | None = None, trace: TraceWriter | None = None,
                 on_replace: Callable[[Replacement], None] | None = None,
                 interfaces: InterfaceOptions | None = None, say: Callable[[str], None] | None = None,
                 cores: int = 1, always_parallel: bool = False):
        self.cache = plugin_cache or PluginCache()
        self.cores = cores
        self.always_parallel = always_parallel
        self.interfaces = interfaces
        self.say = say or (lambda text: None)
        self._load_results: queue.Queue = queue.Queue()  # from the thread checking a sent model
        self._loading = False  # a model sent over the debug link is being checked or swapped in
        self.state = self._prepare(program)
        self.stimulus = stimulus
        self.trace = trace
        self.on_replace = on_replace
        self.sampler = Sampler(trace.columns if trace else columns_of(program))
        self.sampler.bind(program, self.state.published, self.state.charts, self.state.model_devices)
        self.clock = Clock()
        self._earlier_activations: dict[str, int] = {}  # of the programs replaced
        self.native_instants = 0  # instants the runner ran alone (in stretches)
        self.overruns: dict[str, int] = {}
        self.last_time_us: int | None = None
        self.carried: list[CarriedPublication] = []
        self._armed: ProgramState | None = None  # the next program, swapped in at the next instant
        self._armed_lock = threading.Lock()
        self._booted = False

    @property
    def program(self) -> Program:
        return self.state.program

    @property
    def activations(self) -> dict[str, int]:
        """Activations per task name (of every program the run had)."""
        counts = dict(self._earlier_activations)
        for task in self.state.tasks:
            if task.activations:
                counts[task.task.name] = counts.get(task.task.name, 0) + task.activations
        return counts

    def _prepare(self, program: Program) -> ProgramState:
        plugins = self.cache.load_all(program.specs)
        io = None
        if self.interfaces is not None:
            io = Interfaces(Library(program, self.cache))
            if self.interfaces.debug is not None and not io.has_debug:
                raise PluginError(f"model '{program.name}' has no debug interface, which this run serves "
                                  "(declare one: `debug on uart0`)")
        return ProgramState(program, plugins, self.cache.runner, io, ModelDevices(program, self.cache),
                            self.multicore_plan(program))

    def multicore_plan(self, program: Program):
        """The IR's multi-core plan of ``program`` on the engine's cores,
        or None where nothing runs on more than one core."""
        if self.cores <= 1:
            return None
        from ..ir.multicore import plan

        found = plan(program, self.cores, always=self.always_parallel)
        return found if found.parallel else None

    @property
    def io(self) -> Interfaces | None:
        """The running program's interfaces library (None without --debug,
        --modbus-*)."""
        return self.state.io

    def _open_interfaces(self, state: ProgramState) -> None:
        """Write the maps, then open (or adopt) the links and take what
        persistent storage holds: a client that sees a link finds its map
        complete (each written whole, then renamed into place)."""
        o = self.interfaces
        if o.maps is not None:
            o.maps.mkdir(parents=True, exist_ok=True)
            for name, path in state.io.library.files.items():
                if name.endswith((".json", ".csv", ".md")):
                    partial = o.maps / f".{name}.partial"
                    shutil.copyfile(path, partial)
                    os.replace(partial, o.maps / name)
        if not state.io.open(o.debug, o.modbus_tcp, o.modbus_rtu, o.nvram):
            raise InterfaceError("the debug or service interface cannot be opened")
        state.io.pull(state.published)

    def serve_interfaces(self, call: Callable, *args) -> None:
        """A call into the interfaces library (see ProgramState.serve), then
        what it asked for: a model to check, a clock to resynchronise."""
        state, io = self.state, self.state.io
        while not self._load_results.empty():
            io.load_result(*self._load_results.get())
        state.serve(call, *args)
        if io.take_resync():
            self.clock.resync(self.next_time_us())
        text = io.take_load()
        if text is not None:
            self._loading = True
            threading.Thread(target=self._check_sent_model, args=(text,), name="easylab-load", daemon=True).start()

    def _check_sent_model(self, text: bytes) -> None:
        """Front end and build of a model sent over the debug link; a good
        one is swapped in at the next instant, a bad one is refused."""
        from ..pipeline import lower_file

        running = f"program 0x{self.program.program_id:08x} runs on"
        path = self.interfaces.model or Path(self.program.source)
        try:
            program, result = lower_file(path, self.interfaces.schedule, text=text.decode("utf-8"))
        except (UnicodeDecodeError, OSError, ValueError) as err:
            program, result = None, None
            message = f"{path}: {err}"
        if program is None:
            if result is not None:
                first = result.diagnostics.sorted()
                message = first[0].render(result.sources).splitlines()[0] if first else "refused"
            self.say(f"easylab {self.command}: a model sent by the debugger was refused: {message}; {running}")
            self._load_results.put((LOAD_REFUSED, 0, message))
            self._loading = False
            return
        if self.is_running(program):  # nothing to replace
            self._load_results.put((LOAD_REPLACED, program.program_id, "unchanged: the running program"))
            self._loading = False
            return
        try:
            self.replace_model(program)
        except PluginError as err:
            self.say(f"easylab {self.command}: a model sent by the debugger was refused: {err}; {running}")
            self._load_results.put((LOAD_REFUSED, 0, str(err).splitlines()[0]))
            self._loading = False

    # ------------------------------------------------------------ running

    def boot(self) -> None:
        """Open and start devices (nothing to do when simulated), then the
        actors' ``start`` code, in instance order."""
        if not self._booted:
            self._booted = True
            self.state.boot()
            if self.state.io is not None:
                self._open_interfaces(self.state)

    def shutdown(self) -> None:
        """Actors' ``stop`` code, then close the trace (ending the VCD after
        the last traced tick)."""
        if self._booted:
            self._booted = False
            self.state.shutdown()
            if self.state.io is not None:
                self.state.io.close()
        if self.trace is not None:
            end = None if self.last_time_us is None else self.last_time_us + self.program.tick_us
            self.trace.close(end)

    def next_time_us(self) -> int:
        """The logical time of the next instant to process."""
        t = self._instant_time_us()
        if self.carried:
            t = min(t, self.carried[0].due_us)
        return t

    def run(self, duration_us: int | None = None, clock: Clock | None = None,
            instants: int | None = None) -> None:
        """Process instants until logical time ``duration_us`` (that instant
        excluded, as the host board does), ``instants`` instants, or until
        the clock is stopped. Boots first if needed; does not shut down."""
        self.boot()
        if clock is not None:
            self.clock = clock
        done = 0
        while instants is None or done < instants:
            if self._native():
                ran = self._run_native(duration_us, None if instants is None else instants - done)
                if ran:
                    done += ran
                    continue
            t = self.next_time_us()
            if duration_us is not None and t >= duration_us:
                self._wait(duration_us)  # a real-time run lasts its duration
                break
            if not self._wait(t):
                break
            self.step()
            done += 1

    def _native(self) -> bool:
        """Whether the next instants may run in the runner alone: in virtual
        time, with nothing to record, serve or swap in between, from an
        instant that needs no Python."""
        state = self.state
        return (self.trace is None and state.io is None and self.clock.pace is None and self._armed is None
                and not self.clock.stopped and state.instants[state.cursor.index].native)

    def _run_native(self, duration_us: int | None, instants: int | None) -> int:
        """A stretch of instants in one call of the runner (ProgramState.
        run_native), up to the duration, a carried publication's deadline,
        the stimulus's next write, ``instants``, or a bounded amount of work
        (so that a signal or a replacement is never kept waiting long)."""
        before = duration_us if duration_us is not None else NEVER_US
        if self.carried:
            before = min(before, self.carried[0].due_us)
        if self.stimulus is not None:
            quiet = self.stimulus.quiet_until(self._instant_time_us())
            before = before if quiet is None else min(before, quiet)
        limit = NATIVE_INSTANTS if instants is None else min(instants, NATIVE_INSTANTS)
        ran = self.state.run_native(before, limit, NATIVE_OPS)
        if ran:
            self.last_time_us = self.state.cursor.now_us
            self.native_instants += ran
        return ran

    def _wait(self, time_us: int) -> bool:
        """Wait for logical time ``time_us`` (the interfaces served meanwhile,
        at least once per instant); False when the clock was stopped."""
        io = self.state.io
        if io is None:
            return self.clock.wait_until(time_us)
        if self.clock.pace is None:  # virtual time: answer what is there, never wait
            self.serve_interfaces(io.idle, 0)
            return not self.clock.stopped

        def idle(seconds: float) -> None:
            if seconds >= 0.001:
                self.serve_interfaces(io.idle, int(seconds * 1000))
            else:  # below poll()'s millisecond: look, then sleep the rest
                self.serve_interfaces(io.idle, 0)
                time.sleep(max(0.0, seconds))
        if self.clock.remaining_s(time_us) <= 0:
            self.serve_interfaces(io.idle, 0)
        return self.clock.wait_until(time_us, idle)

    def step(self) -> None:
        """One instant (docs/ir.md): publish, inputs, device reads, release,
        trace, task bodies; a pending replacement swaps in after publishing."""
        t = self.next_time_us()
        state = self.state
        while self.carried and self.carried[0].due_us <= t:
            self.carried.pop(0).deliver(state)
        plan = self._instant_at(t)
        if plan is not None:
            state.publish(plan)
        if self._armed is not None:
            with self._armed_lock:
                new, self._armed = self._armed, None
            self._swap(t, new)
            state = self.state
            plan = self._instant_at(t)
        if plan is None:  # a time only a carried publication had
            self._record(t)
            return
        if self.stimulus is not None:
            self.stimulus.apply_inputs(t, state.published)
        if state.io is not None:  # EL_DEBUG_INSTANT: queued writes apply; halts at an instant
            state.io.set_tick(t // self.program.tick_us)
            self.serve_interfaces(state.io.instant)
            state = self.state
        released = plan.released
        # Without interfaces (hooks around each body) in virtual time (no
        # lateness), the bodies that need no Python run with the releases,
        # before the trace records: they change no published value.
        inline = state.io is None and self.clock.pace is None
        if released:
            for device, readers in state.readers:
                if readers.isdisjoint(released):
                    continue
                if state.model_devices is not None and \
                        state.model_devices.read(device, state.published, self.stimulus, t):
                    continue  # its host handlers from the model's folder
                if self.stimulus is not None:
                    self.stimulus.read_device(device, t, state.published)
        if state.io is not None and state.io.forcing:  # EL_DEBUG_FORCE: forced values over what was read;
            self.serve_interfaces(state.io.force)      # conditional breakpoints
            state = self.state
        if released:
            state.release(plan, t, inline)
        self._record(t)
        # Tasks released together on the cores (--cores) run at once here
        # too; with interfaces each body has its hooks, so one by one.
        grouped = not inline and state.io is None and plan.group_bodies is not None
        if grouped:
            state.group_bodies(plan)
        for task_id in plan.python if inline else released:
            task_state = state.tasks[task_id]
            if not grouped or task_id not in plan.inline:
                state.body(task_state)
            if self.clock.late_us(t) > task_state.task.deadline * self.program.tick_us:
                self.overruns[task_state.task.name] = self.overruns.get(task_state.task.name, 0) + 1
        self._advance()

    def _record(self, t: int) -> None:
        self.last_time_us = t
        if self.trace is not None:
            self.trace.record(t, self.sampler.snapshot())

    # ------------------------------------------------------------ the table

    def _instant_time_us(self) -> int:
        cursor = self.state.cursor
        return (cursor.base + self.state.instants[cursor.index].tick) * self.program.tick_us

    def _instant_at(self, t: int) -> InstantPlan | None:
        return self.state.instants[self.state.cursor.index] if self._instant_time_us() == t else None

    def _advance(self) -> None:
        cursor = self.state.cursor
        cursor.index += 1
        if cursor.index == len(self.state.instants):
            cursor.index = 0
            cursor.base += self.program.hyperperiod

    def _position(self, t: int) -> None:
        """Point at the program's first instant at or after time ``t``."""
        tick_us, hyper = self.program.tick_us, self.program.hyperperiod
        tick = -(-t // tick_us)
        cursor = self.state.cursor
        cursor.base = tick // hyper * hyper
        index = next((k for k, x in enumerate(self.state.instants) if cursor.base + x.tick >= tick), None)
        if index is None:
            cursor.base += hyper
            index = 0
        cursor.index = index

    # ------------------------------------------------------------ replacement

    def is_running(self, program: Program) -> bool:
        """Whether ``program`` is the running one: the same IR (program id)
        and the same actor code (plug-in digests)."""
        from .plugins import plugin_source

        running = self.state
        if program.program_id != running.program.program_id:
            return False
        try:
            digests = [self.cache.digest(plugin_source(s)) for s in program.specs]
        except (OSError, ValueError):
            return False
        return digests == [p.digest for p in running.plugins]

    def replace_model(self, new_program: Program) -> None:
        """Swap in ``new_program`` at the next instant.

        Its plug-ins are built and loaded now (a PluginError leaves the
        running program untouched); the swap itself happens in the next
        :meth:`step`, after that instant's publications, so no activation's
        outputs are lost. Safe to call from another thread than the one
        running the engine; a later call before the swap supersedes this one.
        """
        prepared = self._prepare(new_program)
        with self._armed_lock:
            self._armed = prepared

    def _swap(self, t: int, new: ProgramState) -> None:
        old = self.state
        report = Replacement(t, old.program.program_id, new.program.program_id)
        if old.io is not None:  # the links move to the new library: clients stay connected
            old.io.handover()
            old.io.close()
            self._open_interfaces(new)
            if self._loading:
                new.io.load_result(LOAD_REPLACED, new.program.program_id)
                self._loading = False
        for task_state in old.tasks:
            if task_state.pending:
                self.carried.append(carry(old, task_state))
                report.carried_tasks.append(task_state.task.name)
        self.carried.sort(key=lambda c: c.due_us)
        transfer(old, new, report)
        new.model_devices.take_over(old.model_devices, old.published, new.published)
        for task in old.tasks:
            if task.activations:
                name = task.task.name
                self._earlier_activations[name] = self._earlier_activations.get(name, 0) + task.activations
        self.state = new
        self._position(t)
        if self.stimulus is not None:
            self.stimulus.bind(new.program)
            report.ignored_stimulus = list(self.stimulus.unbound)
        report.frozen = self.sampler.bind(new.program, new.published, new.charts, new.model_devices)
        traced = {c.name for c in self.sampler.columns}
        report.untraced = [i.name for i in new.program.items if i.name not in traced] + \
                          [c.name for c in new.program.charts if c.name not in traced]
        if self.on_replace is not None:
            self.on_replace(report)
