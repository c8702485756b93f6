"""The ``easylab`` command line.

Every failure a user can cause (a bad model, a missing file, a missing
tool) ends in one clear message and a non-zero exit status, never in a
Python traceback.
"""

from __future__ import annotations

import argparse
import sys

from .. import __version__
from ..analysis.sdf.analysis import SCHEDULE_KINDS
from . import board_commands, model_commands
from .common import EXIT_MODEL_ERROR, EXIT_USAGE, CliError, add_board_options, cores_arg


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
    p.set_defaults(func=model_commands.cmd_check)

    p = sub.add_parser("graph", help="draw devices, dataflows and charts (Graphviz)",
                       description="Write a Graphviz DOT drawing of the model's devices, each dataflow and "
                                   "each chart; with -o x.svg or x.png render it with Graphviz's dot; with "
                                   "--serve show it in a browser page, redrawn when the model is saved.")
    p.add_argument("file", metavar="FILE", help="model file (.elab)")
    p.add_argument("-o", "--output", metavar="OUT", help="output file: .dot, .svg, .png or .pdf "
                                                         "(default: DOT on standard output)")
    p.add_argument("--serve", action="store_true",
                   help="serve the drawing to a browser, redrawn when the model or an import is saved; "
                        "a click on an element shows its file:line")
    p.add_argument("--listen", metavar="ADDR:PORT", default=None,
                   help="with --serve: where to listen (default 127.0.0.1:8470; port 0: any free port)")
    p.set_defaults(func=model_commands.cmd_graph)

    from .fmt_command import add_parser as add_fmt_parser
    add_fmt_parser(sub)

    p = sub.add_parser("analyze", help="SDF analysis: repetitions, schedules, buffers",
                       description="Analyse the dataflows of a model (.elab) or an SDF3 XML graph (.xml): "
                                   "repetition vector, schedule in looped notation, buffer sizes and bounds.")
    p.add_argument("file", metavar="FILE", help="model file (.elab) or SDF3 graph (.xml)")
    p.add_argument("--dataflow", metavar="NAME", help="only this dataflow")
    p.add_argument("--schedule", choices=SCHEDULE_KINDS,
                   help="schedule kind (default: the dataflow's own choice, else sas)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--cores", type=cores_arg, metavar="N",
                   help="the multi-core plan on N cores: each dataflow's firings list-scheduled, its predicted "
                        "time against one core, the placement of tasks released together (docs/multicore.md)")
    p.add_argument("--profile", action="store_true",
                   help="with --cores: measure each firing's cost by a profiling run of the host build")
    p.add_argument("--stimulus", metavar="CSV", help="with --profile: the run's stimulus (default: MODEL.stimulus.csv "
                                                     "beside the model, if any)")
    p.add_argument("--duration", default="2s", metavar="T",
                   help="with --profile: the run's logical duration (default: 2s)")
    p.set_defaults(func=model_commands.cmd_analyze)

    p = sub.add_parser("build", help="generate C for a board and compile it",
                       description="Generate C from a model for a board and compile it with the board's "
                                   "toolchain into build/<model>/<board>/ (or -o DIR). The path of the "
                                   "program built is printed on the last line. A model of nodes is built "
                                   "node by node, each on its own board, into build/<model>/<node>/, with "
                                   "its round tables in build/<model>/rounds.json.")
    p.add_argument("file", metavar="FILE", help="model file (.elab)")
    add_board_options(p, "the board's MCU (default: the board's own; `easylab boards` lists them; a model of nodes "
                         "names its own)", board_default=None, board_help="; a model of nodes names its own")
    p.add_argument("--release", action="store_true", help="a release build: no debug interface")
    p.add_argument("--schedule", choices=SCHEDULE_KINDS,
                   help="schedule kind of every dataflow (default: each dataflow's own, else sas)")
    p.add_argument("-o", "--output", metavar="DIR", help="output folder")
    p.add_argument("--cc", metavar="CC", help="use this C compiler instead of the board's")
    p.add_argument("--cflags", metavar="FLAGS", help="extra compiler flags, e.g. \"-fsanitize=address,undefined\"")
    p.add_argument("--sim", action="store_true", help="a simulation build and the board's simulator, built beside "
                                                      "it (docs/boards.md)")
    p.add_argument("--check", action="store_true", help="the board's further checks of the C, if it has any "
                                                        "(docs/boards.md)")
    p.add_argument("--cores", type=cores_arg, metavar="N",
                   help="run on N cores where the analysis says it pays (host board; docs/multicore.md)")
    p.add_argument("--parallel", choices=("auto", "always"), default="auto",
                   help="with --cores: 'always' runs every dataflow and task group in parallel whatever the "
                        "prediction (default: auto)")
    p.set_defaults(func=model_commands.cmd_build)

    board_commands.add_parsers(sub)

    from .run_command import add_parser as add_run_parser
    add_run_parser(sub)
    from .launch_command import add_parser as add_launch_parser
    add_launch_parser(sub)
    from .remote_commands import add_parsers as add_remote_parsers
    add_remote_parsers(sub)
    from .lsp_command import add_parser as add_lsp_parser
    add_lsp_parser(sub)
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
