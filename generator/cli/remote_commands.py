"""``easylab proxy`` and ``easylab remote``: remote execution (docs/remote.md).

``proxy`` builds the firmware that runs on the target: the devices of a
model and the instants at which its tasks read and write them, nothing of
the application. ``remote`` runs the application in the interpreter on
this machine with its devices on a running proxy.
"""

from __future__ import annotations

import sys
from pathlib import Path

from ..remote.budget import DEFAULT_BAUD
from ..remote.realtime import POLL_DEADLINES_UP_TO_US, WAITS
from .common import EXIT_OK, EXIT_USAGE, CliError, add_board_options, default_out_dir, lower_model, report_built
from .run_command import add_debug_arguments, add_service_arguments, served_interfaces

EXIT_ERROR = 1


def add_parsers(sub) -> None:
    """Add ``proxy`` and ``remote`` to the ``easylab`` command line."""
    p = sub.add_parser(
        "proxy", help="build the proxy firmware of remote execution",
        description="Generate and compile the proxy of a model for a board: its devices, their data and the "
                    "instants at which its tasks read and write them (the device model), with the link to "
                    "`easylab remote`. The application is not in it: editing it needs no new proxy; editing "
                    "the devices or the tasks' timing does. The path of the program built is printed on the "
                    "last line.")
    p.add_argument("file", metavar="MODEL", help="model file (.elab)")
    add_board_options(p)
    p.add_argument("-o", "--output", metavar="DIR", help="output folder (default: build/<model>/<board>-proxy/)")
    p.add_argument("--sim", action="store_true", help="a simulation build and the board's simulator")
    p.add_argument("--check", action="store_true", help="the board's further checks of the C, if it has any "
                                                        "(docs/boards.md)")
    p.add_argument("--baud", type=int, default=DEFAULT_BAUD,
                   help=f"the link's baud rate where it is a serial port (default {DEFAULT_BAUD}; "
                        "`easylab remote --baud` says the same)")
    p.set_defaults(func=cmd_proxy)

    r = sub.add_parser(
        "remote", help="run a model on this machine with its devices on a proxy",
        description="Interpret the application of a model on this machine (as `easylab run`) while a proxy "
                    "built by `easylab proxy` reads and drives its devices: per instant, one frame each way. "
                    "The trace equals the host firmware's.")
    r.add_argument("file", metavar="MODEL", help="model file (.elab)")
    r.add_argument("--target", metavar="URL", required=True,
                   help="the proxy's link: a serial device, a pty, socket://HOST:PORT (as pyserial opens them)")
    r.add_argument("--baud", type=int, default=DEFAULT_BAUD,
                   help=f"the link's baud rate, as the proxy was built (default {DEFAULT_BAUD})")
    add_board_options(r, mcu_help="the proxy's MCU, as it was built (default: the board's own)",
                      board_help="; the proxy's board, as it was built: the link budget counts its CPU")
    r.add_argument("--connect-timeout", metavar="S", type=float, default=5.0,
                   help="seconds to repeat HELLO until the proxy answers (default 5: opening a serial port "
                        "resets many boards)")
    r.add_argument("--stimulus", metavar="FILE.csv",
                   help="params and vars from a CSV file (the host board's format; device columns are the "
                        "proxy's and are ignored here)")
    r.add_argument("--trace", metavar="FILE", help="record every item and chart at each instant (.csv or .vcd)")
    r.add_argument("--trace-state", action="store_true",
                   help="refused: the devices' `state` fields live on the proxy, whose frames carry only their "
                        "data (docs/remote.md)")
    r.add_argument("--duration", metavar="T", help="stop before logical time T (10s, 500ms, ...); default: endless")
    r.add_argument("--fast", action="store_true",
                   help="lock-step virtual time: the proxy waits for each answer (simulated devices only); "
                        "default: real time, paced by the proxy's clock")
    r.add_argument("--realtime", action="store_true",
                   help="real-time scheduling (SCHED_FIFO) and locked memory for this process where the system "
                        "allows them; at 1 kHz on a busy machine use it with a TCP link (socket://), see "
                        "docs/remote.md")
    r.add_argument("--wait", choices=WAITS, default="auto",
                   help="in real time, wait for the proxy's frames by polling the link (keeps a CPU busy; a "
                        "sleeping process may wake milliseconds late) or by sleeping; default auto: poll at "
                        f"deadlines up to {POLL_DEADLINES_UP_TO_US // 1000} ms unless --realtime")
    r.add_argument("--watch", action="store_true",
                   help="replace the running application when its files change (an edit of the device model is "
                        "refused: the proxy would have to be rebuilt)")
    served = r.add_argument_group(
        "debug and service interfaces (the firmware's servers, as `easylab run` serves them; in real time a "
        "debugger's halt lets the proxy apply its safe values)")
    add_debug_arguments(served)
    add_service_arguments(served)
    r.set_defaults(func=cmd_remote)


# Why `easylab remote --trace-state` is refused (docs/remote.md, "Device states").
TRACE_STATE_REFUSED = ("--trace-state: the devices' `state` fields live in the proxy's RAM on the target and its "
                       "UP frames carry only the devices' data; trace them with the firmware's or `easylab run`'s "
                       "--trace-state")


def _say(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


def cmd_proxy(args) -> int:
    from ..core.errors import BuildError
    from ..remote.proxy import build_proxy

    program = lower_model(args.file)
    out = Path(args.output) if args.output else default_out_dir(program, f"{args.board}-proxy")
    try:
        built = build_proxy(program, args.board, out, mcu=args.mcu, sim=args.sim, board_path=args.board_path,
                            baud=args.baud, check=args.check)
    except BuildError as err:
        raise CliError(str(err)) from None
    _say_budget(program, args.baud, built.board, args.board)
    return report_built(built)


def _say_budget(program, baud: int, board, board_name: str) -> None:
    """Warn when `easylab remote` will refuse a real-time run
    at ``baud`` on ``board`` (budget.refusal, the same check): the proxy
    serves lock-step runs (--fast) only. The build stands: lock-step runs
    need no budget."""
    from ..remote.budget import cpu_coefficients, refusal
    from ..remote.device_model import device_model

    why = refusal(program, device_model(program), baud, board)
    if why is not None:
        # The options that make `easylab remote` count this board's CPU, where it has figures.
        said = (f" --board {board_name}{f' --mcu {board.mcu}' if board.mcu else ''}"
                if cpu_coefficients(board) is not None else "")
        _say(f"easylab proxy: warning: `easylab remote{said}` will refuse a real-time run at {baud} baud: {why}; "
             f"this proxy serves lock-step runs (easylab remote --fast) only")


def budget_board(args):
    """The board whose proxy `easylab remote` drives (--board, --mcu), for
    the CPU's share of the link budget; a CliError when it is unknown."""
    from ..board.registry import BoardError, load_board
    from ..core.errors import BuildError

    try:
        return load_board(args.board, args.board_path).configure(args.mcu)
    except (BoardError, BuildError) as err:
        raise CliError(str(err)) from None


def _overruns_said(program, model, counters: dict) -> str:
    """The proxy's counts at the end of a run, in the words the proxy uses
    for them (docs/remote.md): an overrun is a proxy task's deadline at
    which the host's values had not come."""
    per_task = ", ".join(f"{program.tasks[model.tasks[k].task].name} {n}"
                         for k, n in enumerate(counters["tasks"]) if n)
    return (f"the proxy counted {counters['overruns']} overruns{f' ({per_task})' if per_task else ''}: the host's "
            f"values came late and the previous values held; {counters['watchdog']} watchdog expiries")


def _keep_real_time(args, program, model, link) -> None:
    """SCHED_FIFO and locked memory with --realtime; polling the link at
    short deadlines (--wait); the objects made so far kept out of the
    garbage collector's passes (a full pass over the interpreter's objects
    takes about 10 ms, ten deadlines at 1 kHz): docs/remote.md, "Real time
    at 1 kHz"."""
    import gc

    from ..remote.budget import link_budget
    from ..remote.realtime import go_real_time, polls_its_link

    if args.realtime:
        for warning in go_real_time(args.target):
            _say(f"easylab remote: {warning}")
        if args.wait == "poll":
            _say("easylab remote: warning: --wait poll with --realtime: a real-time process that polls keeps every "
                 "ordinary process off its CPU (the kernel's workers that deliver a pty's or serial port's bytes "
                 "too), and the kernel throttles a real-time process that never sleeps (kernel.sched_rt_runtime_us)")
    deadline_us = min((b.deadline_us for b in link_budget(program, model, args.baud)), default=None)
    link.poll(polls_its_link(args.wait, args.realtime, deadline_us))
    gc.collect()
    gc.freeze()


def cmd_remote(args) -> int:
    """Run the application against a proxy until the duration or a signal."""
    from ..interp.clock import Clock
    from ..interp.trace import TraceError, TraceWriter, columns_of
    from ..remote.budget import refusal
    from ..remote.device_model import device_model
    from ..remote.host import RemoteEngine
    from ..remote.link import Link, RemoteError
    from ..interp.watch import ModelWatcher
    from .run_command import (SetupError, _on_signals, _restore, boot_served, duration_arg, finish_run, plugins_of,
                              stimulus_arg)

    if args.trace_state:
        _say(f"easylab remote: {TRACE_STATE_REFUSED}")
        return EXIT_USAGE
    try:
        duration = duration_arg(args, "remote")
        program = lower_model(args.file)
        model = device_model(program)
        if not args.fast:  # real time: the proxy's clock paces, the link and its CPU must keep up
            why = refusal(program, model, args.baud, budget_board(args))
            if why is not None:
                raise SetupError(f"easylab remote: {why}", EXIT_ERROR)
        cache = plugins_of(program)
        stimulus = stimulus_arg(args, program, "remote")
    except SetupError as err:
        _say(str(err))
        return err.status
    try:
        link = Link(args.target, model, args.baud)
        link.connect(args.connect_timeout)
    except RemoteError as err:
        _say(f"easylab remote: {err}")
        return EXIT_ERROR
    trace = None
    try:
        if args.trace is not None:
            trace = TraceWriter(args.trace, program, columns_of(program))
    except TraceError as err:
        _say(f"easylab remote: {err}")
        link.close()
        return EXIT_USAGE
    def replaced(report) -> None:
        _say(f"easylab remote: at {report.time_us / 1e6:.6f} s the program id changed from 0x{report.old_id:08x} "
             f"to 0x{report.new_id:08x} (the proxy runs on)")

    interfaces = served_interfaces(args)
    clock = Clock(None)  # virtual: the proxy's frames pace the run
    handlers = _on_signals(clock)  # before the interfaces chain their own
    engine, failed = boot_served(lambda: RemoteEngine(program, model, link, stimulus, plugin_cache=cache, trace=trace,
                                                      say=_say, on_replace=replaced, interfaces=interfaces),
                                 clock, args, trace, "remote")
    if engine is None:
        _restore(handlers)
        link.close()
        return failed
    watcher = ModelWatcher(args.file, engine, _say) if args.watch else None
    status = EXIT_OK
    try:
        if watcher:
            watcher.start()
        engine.boot()  # before START: the proxy's clock runs from then on, the first deadlines included
        if not args.fast:
            _keep_real_time(args, program, model, link)
        link.start(lock_step=args.fast)
        engine.run(duration, clock)
        counters = link.counters()
        engine.take_counters(counters, engine.last_time_us or 0)  # the last counts: status items and trace
        if counters["overruns"] or counters["watchdog"]:
            _say(f"easylab remote: {_overruns_said(program, model, counters)}")
        if engine.behind:
            _say(f"easylab remote: {engine.behind_said()}")
    except (RemoteError, OSError, ValueError) as err:  # the link, the trace, a frame not of this model
        _say(f"easylab remote: {err}")
        status = EXIT_ERROR
    finally:
        if not finish_run(engine, watcher, handlers, "remote"):
            status = EXIT_ERROR
        try:
            link.stop()
        except RemoteError:
            pass  # the proxy is gone: its watchdog applies the safe values
        link.close()
    return status
