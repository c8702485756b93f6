"""The model commands of ``easylab``: check, graph, analyze, build."""

from __future__ import annotations

import json
import sys
from pathlib import Path

from ..analysis import sdf
from .common import (DEFAULT_BOARD, EXIT_MODEL_ERROR, EXIT_OK, CliError, check_model, default_out_dir, lower_model,
                     report_built)


def cmd_check(args) -> int:
    status = EXIT_OK
    for path in args.files:
        try:
            result = check_model(path)
        except CliError as err:  # one unreadable file: say so, check the others
            print(f"easylab: error: {err}", file=sys.stderr)
            status = EXIT_MODEL_ERROR
            continue
        if result.model is None:
            print(result.report(), file=sys.stderr)
            count = len(result.diagnostics.sorted())
            print(f"{path}: {count} error{'s' if count != 1 else ''}", file=sys.stderr)
            status = EXIT_MODEL_ERROR
        elif result.model.nodes and _node_problems(result):
            status = EXIT_MODEL_ERROR
        elif result.model.remote is not None and _remote_problems(result):
            status = EXIT_MODEL_ERROR
        elif not args.quiet:
            m = result.model
            print(f"{path}: ok (model '{m.name}': {len(m.devices)} devices, {len(m.dataflows)} dataflows, "
                  f"{len(m.charts)} charts, {len(m.tasks)} tasks)")
    return status


def _node_problems(result) -> bool:
    """Print what keeps a distributed model's nodes off their boards; whether there was anything."""
    from ..board.nodes import node_problems
    from ..ir.lower import lower

    problems = node_problems(lower(result.model, result.timing))
    for problem in problems:
        print(problem, file=sys.stderr)
    return bool(problems)


def _remote_problems(result) -> bool:
    """Report what `easylab proxy` would refuse in the model's `remote`
    settings (device_model.watchdog_problem, the same rule) as an error at
    the watchdog time; whether there was anything."""
    from ..ir.lower import lower
    from ..remote.device_model import watchdog_problem

    problem = watchdog_problem(lower(result.model, result.timing))
    if problem is None:
        return False
    decl = result.model.remote.decl
    span = next((a.value.span for a in decl.attrs if a.key == "watchdog"), decl.span)
    result.diagnostics.error(span, problem)
    print(result.report(), file=sys.stderr)
    print(f"{result.model.file}: 1 error", file=sys.stderr)
    return True


def _checked_model(path: str):
    result = check_model(path)
    if result.model is None:
        print(result.report(), file=sys.stderr)
        raise SystemExit(EXIT_MODEL_ERROR)
    return result.model


def cmd_graph(args) -> int:
    from ..frontend.graph import render_dot, write_graph

    if args.serve:
        if args.output is not None:
            raise CliError("graph: --serve shows the drawing in a browser: give no -o with it")
        from .graph_serve import DEFAULT_LISTEN, serve
        return serve(args.file, args.listen or DEFAULT_LISTEN)
    if args.listen is not None:
        raise CliError("graph: --listen goes with --serve")
    model = _checked_model(args.file)
    dot = render_dot(model)
    if args.output is None:
        sys.stdout.write(dot)
        return EXIT_OK
    try:
        write_graph(dot, Path(args.output))
    except (OSError, RuntimeError) as err:
        raise CliError(str(err)) from None
    print(args.output)
    return EXIT_OK


def cmd_analyze(args) -> int:
    try:
        return _analyze(args)
    except OSError as err:
        raise CliError(f"{args.file}: {err.strerror or err}") from None


def _analyze(args) -> int:
    """``easylab analyze FILE [--dataflow NAME] [--schedule KIND] [--json]``."""
    path = Path(args.file)
    if getattr(args, "profile", False) and not getattr(args, "cores", None):
        raise CliError("--profile measures the costs of the multi-core plan: give --cores N too")
    if getattr(args, "cores", None):
        return _analyze_cores(args, path)
    if path.suffix.lower() == ".xml":
        try:
            graph = sdf.load_sdf3(path)
            result = sdf.analyze(graph, args.schedule or "sas")
        except sdf.SdfError as err:
            print(f"{path}: error: {err.message}", file=sys.stderr)
            return 1
        name = graph.name or path.stem
        if args.json:
            print(json.dumps({"dataflows": [result.to_json_dict(name)]}, indent=2))
        else:
            sys.stdout.write(result.render_text(name))
        return 0
    from ..pipeline import check_file

    checked = check_file(path, schedule=args.schedule)
    if checked.model is None:
        print(checked.report(), file=sys.stderr)
        return 1
    flows = list(checked.model.dataflows.values())
    if args.dataflow:
        flows = [df for df in flows if df.name == args.dataflow]
        if not flows:
            names = ", ".join(checked.model.dataflows) or "none"
            print(f"easylab: error: model '{checked.model.name}' has no dataflow '{args.dataflow}' "
                  f"(its dataflows: {names})", file=sys.stderr)
            return 1
    from ..analysis.distribution import render_round, round_summary

    # A model of nodes: its Modbus links' rounds too (not when one dataflow is asked for)
    rounds = list(checked.timing.links.rounds.values()) if checked.timing.links and not args.dataflow else []
    if args.json:
        found = {"dataflows": [df.analysis.summary() for df in flows]}
        if rounds:
            found["rounds"] = [round_summary(r) for r in rounds]
        print(json.dumps(found, indent=2))
    else:
        sys.stdout.write("\n".join([df.analysis.render_text() for df in flows] + [render_round(r) for r in rounds]))
    return 0


def _analyze_cores(args, path: Path) -> int:
    """``easylab analyze MODEL --cores N [--profile] [--json]``: the multi-core plan (docs/multicore.md)."""
    from ..ir import multicore

    if path.suffix.lower() == ".xml":
        raise CliError(f"{path}: --cores plans a model's dataflows and tasks: give a model file (.elab)")
    program = lower_model(args.file, args.schedule)
    costs = _profile_costs(program, path, args.stimulus, args.duration) if args.profile else {}
    found = multicore.plan(program, args.cores, costs)
    if args.dataflow:
        found.dataflows = [p for p in found.dataflows if p.dataflow.name == args.dataflow]
        if not found.dataflows:
            names = ", ".join(df.name for df in program.dataflows) or "none"
            raise CliError(f"model '{program.name}' has no dataflow '{args.dataflow}' (its dataflows: {names})")
    if args.json:
        summary = found.summary()
        summary["costs"] = "profile" if args.profile else "declared"
        print(json.dumps(summary, indent=2))
    else:
        sys.stdout.write(found.render_text())
    return 0


def _profile_costs(program, path: Path, stimulus: str | None, duration: str) -> dict[str, int]:
    """ns per firing by "dataflow.node", from a profiling run of the host
    build with ``stimulus``, else the model's MODEL.stimulus.csv beside it
    if there is one."""
    import tempfile

    from .profile import ProfileError, profile_program

    beside = path.with_suffix(".stimulus.csv")
    found = Path(stimulus) if stimulus else (beside if beside.exists() else None)
    with tempfile.TemporaryDirectory(prefix="easylab-profile-") as tmp:
        try:
            return profile_program(program, Path(tmp), found, duration)
        except ProfileError as err:
            raise CliError(str(err)) from None


def cmd_build(args) -> int:
    """``easylab build FILE``: one board's program, or a model of nodes node by node."""
    import shlex

    from ..build import BuildError, build

    program = lower_model(args.file, args.schedule)
    if program.deployment is not None:
        return _build_nodes(program, args)
    board = args.board or DEFAULT_BOARD
    out = Path(args.output) if args.output else default_out_dir(program, board)
    try:
        built = build(program, board, out, extra_cflags=shlex.split(args.cflags or ""), cc=args.cc,
                      release=args.release, mcu=args.mcu, sim=args.sim, schedule=args.schedule,
                      board_path=args.board_path, check=args.check, cores=args.cores or 1,
                      always_parallel=args.parallel == "always")
    except BuildError as err:
        raise CliError(str(err)) from None
    return report_built(built)


def _build_nodes(program, args) -> int:
    """A model of nodes: every node on its own board, into
    build/<model>/<node>/, and the round tables of its Modbus links in
    rounds.json beside them. Its nodes name their boards, MCUs and
    compilers: --board, --mcu and --cc are refused."""
    import shlex

    from ..analysis.distribution import round_summary
    from ..build import BuildError, build_nodes

    given = [f"{option} {value}" for option, value in (("--board", args.board), ("--mcu", args.mcu), ("--cc", args.cc),
                                                       ("--cores", getattr(args, "cores", None)))
             if value is not None]
    if given:
        nodes = ", ".join(f"{n.name} on {n.board}{f' ({n.mcu})' if n.mcu else ''}" for n in program.deployment.nodes)
        raise CliError(f"{args.file}: model '{program.name}' has nodes, and each node names its board and MCU in the "
                       f"model ({nodes}); {' and '.join(given)} would choose for all of them: build without "
                       f"{'it' if len(given) == 1 else 'them'}, or change a node's declaration "
                       f"(`node NAME board B mcu M`, docs/distribution.md)")

    out = Path(args.output) if args.output else Path("build") / program.name
    try:
        built = build_nodes(program, out, extra_cflags=shlex.split(args.cflags or ""), release=args.release,
                            schedule=args.schedule, board_path=args.board_path, check=args.check)
    except BuildError as err:
        raise CliError(str(err)) from None
    for name, node in built.items():
        for note in node.notes:
            print(f"{name}: {note}")
        print(f"{name}: {node.executable}")
    rounds = out / "rounds.json"
    deployment = program.deployment
    rounds.write_text(json.dumps({"model": program.name,
                                  "nodes": {n.name: {"board": n.board, "mcu": n.mcu} for n in deployment.nodes},
                                  "rounds": [round_summary(t) for t in deployment.rounds.values()]},
                                 indent=2) + "\n")
    print(rounds)
    return 0
