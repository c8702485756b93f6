"""``easylab launch``: every node of a model of nodes on this machine, for
a test run (docs/distribution.md, "Launch").

The model is built node by node (``easylab build``); then each MCU node
runs in its board's simulator with its link's UART on a pseudo-terminal,
each other node as a process; the master of a Modbus link reaches each
slave through that slave's pty (EASYLAB_BUS_<node>, boards/host/host_bus.c).
Every node writes its own trace, ``<trace-dir>/<node>.csv``, with the
columns of its own items; a stimulus file is split the same way. The run
ends when the masters (and the other processes) end at ``--duration``; the
slaves, whose ticks follow the master's sync, are then stopped. A slave
that stops answering is reported by the master by name, and the others go
on. Each node's process id is in ``<trace-dir>/<node>.pid`` while it runs.
"""

from __future__ import annotations

import csv
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

from .common import CliError, lower_model

EXIT_OK, EXIT_ERROR = 0, 1
PTY_WAIT_S = 30  # for a simulator to open its UART's pty
SLOW_SLAVE_MS = 20000  # the master's wait for an answer before it calls a slave silent


def add_parser(sub) -> None:
    """The ``launch`` subcommand."""
    p = sub.add_parser("launch", help="start every node of a model of nodes on this machine (a test run)",
                       description="Build a model of nodes node by node and start every node on this machine: "
                                   "MCU nodes in their board's simulator with their Modbus UART on a pty, PC "
                                   "nodes as processes, the master joined to each slave's pty. One trace per "
                                   "node in the trace folder.")
    p.add_argument("file", metavar="FILE", help="model file (.elab) with nodes")
    p.add_argument("--duration", metavar="T", help="stop before logical time T (10s, 500ms, ...)")
    p.add_argument("--fast", action="store_true", help="virtual time: the master runs flat out and the slaves "
                                                       "follow its sync (lock-step)")
    p.add_argument("--stimulus", metavar="FILE.csv", help="a stimulus of the whole model; each node gets its "
                                                          "own columns")
    p.add_argument("--trace-dir", metavar="DIR", help="the nodes' traces (default: launch/<model>/)")
    p.add_argument("--build-dir", metavar="DIR", help="the nodes' builds (default: build/<model>/)")
    p.add_argument("--debug", metavar="pty:LINK|tcp:PORT[,halt]",
                   help="serve the Modbus master's debug interface (its status items: the channels' tardy "
                        "counts, each slave's unanswered frames), as its host program does")
    p.set_defaults(func=cmd_launch)


def _node_stimulus(stimulus: Path, names: set[str], out: Path) -> Path | None:
    """The columns of a stimulus that name one node's items (time first)."""
    with stimulus.open(newline="") as f:
        rows = list(csv.reader(f))
    if not rows:
        return None
    keep = [0] + [i for i, name in enumerate(rows[0]) if i > 0 and name.strip() in names]
    if len(keep) == 1:
        return None
    with out.open("w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        for row in rows:
            w.writerow([row[i] for i in keep if i < len(row)])
    return out


def _wait_for(path: Path, proc: subprocess.Popen, node: str) -> None:
    end = time.monotonic() + PTY_WAIT_S
    while not path.exists():
        if proc.poll() is not None or time.monotonic() > end:
            raise CliError(f"node '{node}': its simulator did not open its bus UART ({path})")
        time.sleep(0.02)


def cmd_launch(args) -> int:
    from ..build import BuildError, build_nodes
    from ..ir.split import split

    program = lower_model(args.file, None)
    if program.deployment is None:
        raise CliError(f"model '{program.name}' has no nodes: run it with 'easylab run' or build it for a board")
    build_dir = Path(args.build_dir) if args.build_dir else Path("build") / program.name
    trace_dir = Path(args.trace_dir) if args.trace_dir else Path("launch") / program.name
    trace_dir.mkdir(parents=True, exist_ok=True)
    try:
        built = build_nodes(program, build_dir)
    except BuildError as err:
        raise CliError(str(err)) from None
    nodes = split(program)
    slaves = {s.node: s.uart for table in program.deployment.rounds.values() for s in table.slots}
    masters = {table.master for table in program.deployment.rounds.values()}
    if args.debug and len(masters) != 1:
        raise CliError(f"model '{program.name}' has {len(masters)} Modbus masters: --debug serves one")
    common = (["--fast"] if args.fast else []) + (["--duration", args.duration] if args.duration else [])
    procs: dict[str, subprocess.Popen] = {}
    env = dict(os.environ)
    # a simulated slave may take long in wall time (it delivers its stimulus edge by edge): a dead one
    # closes its pty, which the master sees at once
    env.setdefault("EASYLAB_BUS_TIMEOUT_MS", str(SLOW_SLAVE_MS))
    try:
        for name, node in nodes.items():  # the slaves first: the master opens their ptys
            if name not in slaves:
                continue
            result = built[name]
            cmd = [str(result.simulator or result.executable)] + (["--fast"] if args.fast else [])
            cmd += ["--wait", "--trace", str(trace_dir / f"{name}.csv")]
            if result.simulator:  # the sync and the slot stay two frames on a busy machine
                cmd.append("--rtu-frames")
            uart = slaves[name].replace("[", "").replace("]", "")
            bus = (trace_dir / f"{name}.bus").resolve()
            bus.unlink(missing_ok=True)
            cmd += [f"--{uart}", f"pty:{bus}"]
            cmd += _stimulus_args(args, node, trace_dir, name)
            procs[name] = subprocess.Popen(cmd, stdin=subprocess.DEVNULL)
            _wait_for(bus, procs[name], name)
            env[f"EASYLAB_BUS_{name}"] = str(bus)
        for name, node in nodes.items():
            if name in slaves:
                continue
            cmd = [str(built[name].executable), *common, "--trace", str(trace_dir / f"{name}.csv")]
            cmd += ["--debug", args.debug] if args.debug and name in masters else []
            cmd += _stimulus_args(args, node, trace_dir, name)
            procs[name] = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, env=env)
        for name, proc in procs.items():
            (trace_dir / f"{name}.pid").write_text(f"{proc.pid}\n")
        status = EXIT_OK
        for name, proc in procs.items():
            if name not in slaves and proc.wait() != 0:
                print(f"easylab: node '{name}' ended with status {proc.returncode}", file=sys.stderr)
                status = EXIT_ERROR
    finally:
        for name, proc in procs.items():  # the slaves follow the master: stop them with it
            if proc.poll() is None:
                proc.send_signal(signal.SIGTERM)
        for name, proc in procs.items():
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
            (trace_dir / f"{name}.pid").unlink(missing_ok=True)
    for name in nodes:
        print(f"{name}: {trace_dir / f'{name}.csv'}")
    return status


def _stimulus_args(args, node, trace_dir: Path, name: str) -> list[str]:
    if not args.stimulus:
        return []
    names = {i.name for i in node.program.items}
    own = _node_stimulus(Path(args.stimulus), names, trace_dir / f"{name}.stimulus.csv")
    return ["--stimulus", str(own)] if own else []
