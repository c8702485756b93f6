"""``easylab run``: local execution of a model (docs/local.md).

The options mirror the host board's command line (boards/host/README.md):
``--fast``, ``--duration T``, ``--stimulus FILE.csv``, ``--trace
FILE.csv|FILE.vcd``, with the same formats and the same trace, the
interfaces ``--debug``, ``--modbus-tcp``, ``--modbus-rtu`` and ``--nvram``
(served by the firmware's own servers: interfaces.py), plus ``--maps DIR``,
``--watch`` (live replacement) and ``--pace X`` (virtual time at X times
real time). Exit status: 0 the run ended (duration, SIGINT, SIGTERM); 1 a
model or plug-in error, or an I/O error during the run; 2 a bad command
line or input file, reported before anything runs (no trace is created).
"""

from __future__ import annotations

import re
import signal
import sys
import threading
from fractions import Fraction

from ..analysis.sdf.analysis import SCHEDULE_KINDS
from .common import cores_arg

EXIT_OK, EXIT_ERROR, EXIT_USAGE = 0, 1, 2

_UNITS = {"us": 1, "ms": 1000, "s": 1_000_000, "m": 60_000_000, "min": 60_000_000, "h": 3_600_000_000}
_DURATION = re.compile(r"(\d+)(?:\.(\d+))? ?(.*)")


def parse_duration(text: str) -> int:
    """A duration with a unit ("10s", "1.5s", "500ms", "250us", "2m", "1h";
    one space may separate number and unit), in exact microseconds, as the
    host board reads ``--duration``. Raises ValueError with the reason."""
    m = _DURATION.fullmatch(text)
    if not m:
        raise ValueError("not a duration (give a number and a unit: 10s, 1.5s, 500ms, 250us, 2m, 1h)")
    whole, frac, unit = m.groups()
    if not unit:
        raise ValueError("a duration needs a unit: us, ms, s, m or h (e.g. 10s, 500ms)")
    if unit not in _UNITS:
        raise ValueError("unknown time unit (give us, ms, s, m or h: 10s, 1.5s, 500ms, 250us, 2m)")
    value = (int(whole) + Fraction(f"0.{frac}" if frac else "0")) * _UNITS[unit]
    if value.denominator != 1:
        raise ValueError("duration finer than 1 us")
    if value >= 2 ** 64:
        raise ValueError("duration too long")
    return int(value)


def _positive_float(text: str) -> float:
    import argparse

    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not value > 0 or value == float("inf"):
        raise argparse.ArgumentTypeError("the pace must be a positive number")
    return value


def add_parser(sub) -> None:
    """Add the ``run`` subcommand to the ``easylab`` command line."""
    p = sub.add_parser(
        "run", help="run a model on this machine (interpreter and actor plug-ins)",
        description="Interpret a model on this machine: the IR's dispatch table, charts and dataflows, with "
                    "each actor's C code compiled into a cached plug-in. Devices run as on the host board: the "
                    "host handlers their types bring from the model's folder (a plug-in too), else simulated "
                    "(stimulus CSV in, CSV or VCD trace out); the trace equals the host firmware's.")
    p.add_argument("file", metavar="MODEL", help="model file (.elab)")
    p.add_argument("--stimulus", metavar="FILE.csv", help="device `out` data, params and vars from a CSV file: "
                                                          "time_us, then their names (the host board's format)")
    p.add_argument("--trace", metavar="FILE", help="record every item and chart at each instant (.csv or .vcd)")
    p.add_argument("--trace-state", action="store_true",
                   help="the trace also records the devices' `state` fields (DEVICE.FIELD, after the items), as the "
                        "host firmware's --trace-state")
    p.add_argument("--duration", metavar="T", help="stop before logical time T (10s, 1.5s, 500ms, 250us, 2m, 1h); "
                                                   "default: endless")
    timing = p.add_mutually_exclusive_group()
    timing.add_argument("--fast", action="store_true", help="virtual time: instants follow each other at once")
    timing.add_argument("--pace", metavar="X", type=_positive_float,
                        help="logical time runs X times as fast as real time (default 1: real time)")
    p.add_argument("--watch", action="store_true",
                   help="replace the running model when its files change (state kept for what did not change)")
    p.add_argument("--schedule", choices=SCHEDULE_KINDS,
                   help="schedule kind of every dataflow (default: each dataflow's own, else sas)")
    p.add_argument("--cores", type=cores_arg, metavar="N",
                   help="run the actors on N threads where the analysis says it pays, on the host board's "
                        "plan (docs/multicore.md)")
    p.add_argument("--parallel", choices=("auto", "always"), default="auto",
                   help="with --cores: 'always' runs every dataflow and task group in parallel whatever the "
                        "prediction (default: auto)")
    served = p.add_argument_group("debug and service interfaces (the firmware's servers, as on the host board)")
    add_debug_arguments(served)
    add_service_arguments(served)
    p.set_defaults(func=cmd_run)


def add_debug_arguments(group) -> None:
    """``--debug`` and ``--maps``, as ``run`` and ``remote`` serve them."""
    group.add_argument("--debug", metavar="pty:LINK|tcp:PORT[,halt]",
                       help="serve the debug interface on a new pseudo-terminal (LINK: a symlink to it) or on "
                            "127.0.0.1:PORT; ,halt halts before the first instant")
    group.add_argument("--maps", metavar="DIR", help="write debug_map.json and service_map.* into DIR (at start "
                                                     "and at each replacement)")


def add_service_arguments(group) -> None:
    """``--modbus-tcp``, ``--modbus-rtu`` and ``--nvram``, as ``run`` and ``remote`` serve them."""
    group.add_argument("--modbus-tcp", metavar="PORT", help="serve the model's `modbus tcp` interface on "
                                                            "127.0.0.1:PORT (default: the model's port)")
    group.add_argument("--modbus-rtu", metavar="pty:LINK", help="serve its `modbus rtu` interface on a new "
                                                                "pseudo-terminal")
    group.add_argument("--nvram", metavar="FILE", help="keep `persist` params in FILE (default: in memory)")


def served_interfaces(args, schedule: str | None = None):
    """What a run serves, from its command line: an InterfaceOptions, or
    None for nothing."""
    from pathlib import Path

    from ..interp.engine import InterfaceOptions

    if not (args.debug or args.modbus_tcp or args.modbus_rtu or args.nvram or args.maps):
        return None
    return InterfaceOptions(args.debug, args.modbus_tcp, args.modbus_rtu, args.nvram,
                            Path(args.maps) if args.maps else None, Path(args.file), schedule)


def _say(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


class SetupError(Exception):
    """What stops a run before it starts: the message and the exit status."""

    def __init__(self, message: str, status: int):
        super().__init__(message)
        self.status = status


def duration_arg(args, command: str) -> int | None:
    """``--duration`` in µs (None: endless); SetupError for a bad one."""
    if args.duration is None:
        return None
    try:
        return parse_duration(args.duration)
    except ValueError as err:
        raise SetupError(f"easylab {command}: --duration {args.duration}: {err}", EXIT_USAGE) from None


def plugins_of(program):
    """The plug-in cache with every actor of ``program`` built and loaded;
    SetupError when one does not build."""
    from ..interp.plugins import PluginCache, PluginError

    cache = PluginCache()
    try:
        cache.load_all(program.specs)
    except PluginError as err:
        raise SetupError(f"easylab: error: {err}", EXIT_ERROR) from None
    return cache


def stimulus_arg(args, program, command: str):
    """The ``--stimulus`` file read and checked for ``program`` (None
    without one); SetupError for one that cannot be read or is wrong."""
    from ..interp.stimulus import StimulusError
    from ..interp.stimulus import load as load_stimulus

    if args.stimulus is None:
        return None
    try:
        return load_stimulus(args.stimulus, program)
    except OSError as err:
        raise SetupError(f"easylab {command}: cannot read stimulus {args.stimulus}: {err.strerror or err}",
                         EXIT_USAGE) from None
    except StimulusError as err:
        raise SetupError(str(err), EXIT_USAGE) from None


def cmd_run(args) -> int:
    """Run a model until its duration, a signal, or forever."""
    from ..pipeline import lower_file

    from ..interp.clock import Clock
    from ..interp.engine import Engine
    from ..interp.trace import TraceError, TraceWriter, columns_of
    from ..interp.watch import ModelWatcher

    try:
        duration = duration_arg(args, "run")
    except SetupError as err:
        _say(str(err))
        return err.status
    try:
        program, result = lower_file(args.file, schedule=args.schedule)
    except FileNotFoundError:
        _say(f"easylab: error: {args.file}: no such file")
        return EXIT_ERROR
    except (IsADirectoryError, UnicodeDecodeError):
        _say(f"easylab: error: {args.file}: not a model file")
        return EXIT_ERROR
    if program is None:
        _say(result.report())
        return EXIT_ERROR
    trace = None
    try:
        cache = plugins_of(program)
        stimulus = stimulus_arg(args, program, "run")
        if args.trace is not None:
            trace = TraceWriter(args.trace, program, columns_of(program, args.trace_state))
    except SetupError as err:
        _say(str(err))
        return err.status
    except TraceError as err:
        _say(f"easylab run: {err}")
        return EXIT_USAGE

    def replaced(report) -> None:
        notes = []
        if report.untraced and trace:
            notes.append(f"not traced: {', '.join(report.untraced)}")
        if report.ignored_stimulus:
            notes.append(f"stimulus columns ignored: {', '.join(report.ignored_stimulus)}")
        _say(f"easylab run: at {report.time_us / 1e6:.6f} s the program id changed from "
             f"0x{report.old_id:08x} to 0x{report.new_id:08x}" + (f" ({'; '.join(notes)})" if notes else ""))

    interfaces = served_interfaces(args, args.schedule)
    cores, always = args.cores or 1, args.parallel == "always"
    if cores > 1:
        from ..ir.multicore import plan as multicore_plan

        for note in multicore_plan(program, cores, always=always).notes("a single-core run"):
            _say(f"easylab run: {note}")
    clock = Clock(None if args.fast else (args.pace or 1.0))
    previous_handlers = _on_signals(clock)  # before the interfaces chain their own
    engine, failed = boot_served(lambda: Engine(program, cache, stimulus, trace, on_replace=replaced,
                                                interfaces=interfaces, say=_say, cores=cores, always_parallel=always),
                                 clock, args, trace, "run")
    if engine is None:
        _restore(previous_handlers)
        return failed
    watcher = ModelWatcher(args.file, engine, _say, args.schedule) if args.watch else None
    status = EXIT_OK
    try:
        if watcher:
            watcher.start()
        engine.run(duration, clock)
    except OSError as err:
        _say(f"easylab run: error writing trace {args.trace}: {err.strerror or err}")
        status = EXIT_ERROR
    finally:
        if not finish_run(engine, watcher, previous_handlers, "run"):
            status = EXIT_ERROR
    if engine.overruns:
        _say("easylab run: overruns: " + " ".join(f"{name} {n}" for name, n in engine.overruns.items()))
    return status


def boot_served(make_engine, clock, args, trace, command: str):
    """(engine, None): the engine ``make_engine`` makes, on ``clock`` and
    booted with the interfaces it serves open (``--debug``, ...), having
    said where their maps are when ``--maps`` does not; or (None, exit
    status) when that fails (said on stderr; nothing ran, so no trace file
    is left, as on the host board)."""
    from pathlib import Path

    from ..interp.engine import InterfaceError
    from ..interp.plugins import PluginError

    try:
        engine = make_engine()
        engine.clock = clock
        engine.boot()
    except (PluginError, InterfaceError, OSError) as err:
        if isinstance(err, PluginError):
            _say(f"easylab: error: {err}")
        elif isinstance(err, OSError):
            _say(f"easylab {command}: --maps {args.maps}: {err.strerror or err}")
        if trace is not None:
            trace.file.close()
            Path(args.trace).unlink(missing_ok=True)
        return None, EXIT_ERROR if isinstance(err, PluginError) else EXIT_USAGE
    if engine.interfaces is not None and engine.interfaces.maps is None:
        maps = engine.io.library.directory
        _say(f"easylab {command}: maps of program 0x{engine.program.program_id:08x}: {maps}/debug_map.json, "
             f"{maps}/service_map.json")
    return engine, None


def finish_run(engine, watcher, handlers: dict, command: str) -> bool:
    """The end of a run, however it ended: the watcher stops, the signal
    handlers are restored, the engine shuts down (the trace is closed);
    False when the trace could not be completed (said on stderr)."""
    from ..interp.trace import TraceError

    if watcher:
        watcher.stop()
    _restore(handlers)
    try:
        engine.shutdown()
    except TraceError as err:
        _say(f"easylab {command}: {err}")
        return False
    return True


def _restore(handlers: dict) -> None:
    for sig, handler in handlers.items():
        signal.signal(sig, handler)


def _on_signals(clock) -> dict:
    """SIGINT and SIGTERM end the run at the next instant (the trace is
    complete); a second signal acts as before. Returns the handlers to
    restore afterwards."""
    if threading.current_thread() is not threading.main_thread():
        return {}  # only the main thread may handle signals
    previous = {sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM)}

    def handler(signum, frame):
        clock.stop()
        signal.signal(signum, previous[signum])
    for sig in previous:
        signal.signal(sig, handler)
    return previous
