"""The ``easylab`` command line.

Every failure a user can cause (a bad model, a missing file, a missing
tool) ends in one clear message and a non-zero exit status, never in a
Python traceback.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from . import __version__
from .sdf.analysis import SCHEDULE_KINDS

EXIT_OK, EXIT_MODEL_ERROR, EXIT_USAGE = 0, 1, 2


class CliError(Exception):
    """A failure to report as one line, ``easylab: error: ...``."""


def _check(path: str):
    from .frontend import check_file

    try:
        result = check_file(path)
    except FileNotFoundError:
        raise CliError(f"{path}: no such file") from None
    except IsADirectoryError:
        raise CliError(f"{path}: is a directory, not a model file") from None
    except UnicodeDecodeError:
        raise CliError(f"{path}: not a UTF-8 text file") from None
    except OSError as err:
        raise CliError(f"{path}: {err.strerror or err}") from None
    return result


def cmd_check(args) -> int:
    status = EXIT_OK
    for path in args.files:
        try:
            result = _check(path)
        except CliError as err:  # one unreadable file: say so, check the others
            print(f"easylab: error: {err}", file=sys.stderr)
            status = EXIT_MODEL_ERROR
            continue
        if result.model is None:
            print(result.report(), file=sys.stderr)
            count = len(result.diagnostics.sorted())
            print(f"{path}: {count} error{'s' if count != 1 else ''}", file=sys.stderr)
            status = EXIT_MODEL_ERROR
        elif not args.quiet:
            m = result.model
            print(f"{path}: ok (model '{m.name}': {len(m.devices)} devices, {len(m.dataflows)} dataflows, "
                  f"{len(m.charts)} charts, {len(m.tasks)} tasks)")
    return status


def _checked_model(path: str):
    result = _check(path)
    if result.model is None:
        print(result.report(), file=sys.stderr)
        raise SystemExit(EXIT_MODEL_ERROR)
    return result.model


def cmd_graph(args) -> int:
    from .graph import render_dot, write_graph

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
    from .analysis import analyze_command

    try:
        return analyze_command(args)
    except OSError as err:
        raise CliError(f"{args.file}: {err.strerror or err}") from None


def cmd_build(args) -> int:
    import shlex

    from .boards import BoardError
    from .build import BuildError, build
    from .frontend import lower_file

    try:
        program, result = lower_file(args.file, schedule=args.schedule)
    except FileNotFoundError:
        raise CliError(f"{args.file}: no such file") from None
    except (IsADirectoryError, UnicodeDecodeError):
        raise CliError(f"{args.file}: not a model file") from None
    if program is None:
        print(result.report(), file=sys.stderr)
        return EXIT_MODEL_ERROR
    out = Path(args.output) if args.output else Path("build") / program.name / args.board
    try:
        built = build(program, args.board, out, extra_cflags=shlex.split(args.cflags or ""), cc=args.cc,
                      release=args.release, mcu=args.mcu, sim=args.sim, schedule=args.schedule)
    except (BuildError, BoardError) as err:
        raise CliError(str(err)) from None
    for note in built.notes:
        print(note)
    print(built.executable)
    return EXIT_OK


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="easylab",
        description="Model-based development for robot and mechatronic controllers: "
                    "check, analyse and build .elab models.")
    parser.add_argument("--version", action="version", version=f"easylab {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")

    p = sub.add_parser("check", help="check models and report every error",
                       description="Parse and check model files (and their imports). Errors are printed as "
                                   "file:line:col with the source line; the exit status is 1 if any model "
                                   "has errors.")
    p.add_argument("files", nargs="+", metavar="FILE", help="model files (.elab)")
    p.add_argument("-q", "--quiet", action="store_true", help="print nothing for models without errors")
    p.set_defaults(func=cmd_check)

    p = sub.add_parser("graph", help="draw devices, dataflows and charts (Graphviz)",
                       description="Write a Graphviz DOT drawing of the model's devices, each dataflow and "
                                   "each chart; with -o x.svg or x.png render it with Graphviz's dot.")
    p.add_argument("file", metavar="FILE", help="model file (.elab)")
    p.add_argument("-o", "--output", metavar="OUT", help="output file: .dot, .svg, .png or .pdf "
                                                         "(default: DOT on standard output)")
    p.set_defaults(func=cmd_graph)

    p = sub.add_parser("analyze", help="SDF analysis: repetitions, schedules, buffers",
                       description="Analyse the dataflows of a model (.elab) or an SDF3 XML graph (.xml): "
                                   "repetition vector, schedule in looped notation, buffer sizes and bounds.")
    p.add_argument("file", metavar="FILE", help="model file (.elab) or SDF3 graph (.xml)")
    p.add_argument("--dataflow", metavar="NAME", help="only this dataflow")
    p.add_argument("--schedule", choices=SCHEDULE_KINDS,
                   help="schedule kind (default: the dataflow's own choice, else sas)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=cmd_analyze)

    p = sub.add_parser("build", help="generate C for a board and compile it",
                       description="Generate C from a model for a board and compile it with the board's "
                                   "toolchain into build/<model>/<board>/ (or -o DIR). The path of the "
                                   "program built is printed on the last line.")
    p.add_argument("file", metavar="FILE", help="model file (.elab)")
    p.add_argument("--board", default="host", help="target board (default: host)")
    p.add_argument("--release", action="store_true", help="a release build: no debug interface")
    p.add_argument("--schedule", choices=SCHEDULE_KINDS,
                   help="schedule kind of every dataflow (default: each dataflow's own, else sas)")
    p.add_argument("-o", "--output", metavar="DIR", help="output folder")
    p.add_argument("--cc", metavar="CC", help="use this C compiler instead of the board's")
    p.add_argument("--cflags", metavar="FLAGS", help="extra compiler flags, e.g. \"-fsanitize=address,undefined\"")
    p.add_argument("--mcu", metavar="MCU", help="the MCU of a cross board (avr: atmega328p, the default, or "
                                                "atmega2560)")
    p.add_argument("--sim", action="store_true", help="a simulation build (avr: instants reported to the simavr "
                                                      "harness, which is built beside the ELF)")
    p.set_defaults(func=cmd_build)

    from .interp.cli import add_parser as add_run_parser
    add_run_parser(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``easylab`` console script."""
    parser = build_parser()
    argv = list(sys.argv[1:] if argv is None else argv)
    # `--cflags -O0`: argparse takes a value starting with '-' for an option;
    # join it to its option so that both spellings work.
    for i, arg in enumerate(argv[:-1]):
        if arg == "--cflags":
            argv[i:i + 2] = [f"--cflags={argv[i + 1]}"]
            break
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return EXIT_USAGE
    try:
        return args.func(args)
    except CliError as err:
        print(f"easylab: error: {err}", file=sys.stderr)
        return EXIT_MODEL_ERROR
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":
    sys.exit(main())
