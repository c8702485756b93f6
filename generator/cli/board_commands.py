"""The board commands of ``easylab``: ``boards`` (what boards there are),
``flash`` (burn a build into a board) and ``sim`` (run a simulation
build). What each does is the board's (the board contract); the Makefile's
``flash`` and ``sim`` targets call these."""

from __future__ import annotations

import json
import shlex
import subprocess
from pathlib import Path

from ..board.contract import BoardCannotRun
from ..board.registry import board_folders, load_board, search_path
from ..core.errors import BuildError
from .common import EXIT_OK, CliError, add_board_options, default_out_dir, lower_model


def cmd_boards(args) -> int:
    try:
        if args.default_mcu:
            print(load_board(args.default_mcu, args.board_path).configure().mcu or "")
            return EXIT_OK
        rows = []
        for name, where in sorted(board_folders(args.board_path).items()):
            board = load_board(name, args.board_path)
            rows.append({"name": name, "folder": str(where.folder), "installed": where.installed,
                         "title": board.description.title, "mcus": board.mcus(),
                         "default_mcu": board.configure().mcu, "simulator": bool(board.has_simulator)})
    except BuildError as err:
        raise CliError(str(err)) from None
    if args.json:
        print(json.dumps({"search_path": [str(p) for p in search_path(args.board_path)], "boards": rows}, indent=2))
        return EXIT_OK
    for r in rows:
        mcus = f" (MCUs: {', '.join(r['mcus'])}; default {r['default_mcu']})" if r["mcus"] else ""
        where = "" if r["installed"] else f" [{r['folder']}]"
        print(f"{r['name']}{where}: {r['title']}{mcus}{'' if r['simulator'] else '; no simulator here'}")
    return EXIT_OK


def _board_and_program(args):
    program = lower_model(args.file)
    try:
        board = load_board(args.board, args.board_path).configure(args.mcu, sim=getattr(args, "simulation", False))
    except BuildError as err:
        raise CliError(str(err)) from None
    out = Path(args.output) if args.output else default_out_dir(program, args.board)
    return board, program, out


def _run(command: list[str], dry: bool) -> int:
    print(shlex.join(command), flush=True)
    if dry:
        return EXIT_OK
    try:
        return subprocess.run(command).returncode
    except FileNotFoundError:
        raise CliError(f"{command[0]} is not installed (or not on PATH)") from None


def cmd_flash(args) -> int:
    board, program, out = _board_and_program(args)
    if args.proxy:  # the remote-execution proxy `easylab proxy` built (docs/remote.md)
        from ..remote.device_model import proxy_program
        out = Path(args.output) if args.output else default_out_dir(program, f"{args.board}-proxy")
        program = proxy_program(program)
    try:
        command = board.flash_command(out, program, args.port, args.programmer, args.baud)
    except BuildError as err:
        raise CliError(str(err)) from None
    if not args.print and not any(Path(a).is_file() for a in command if str(out) in a):
        build = "proxy" if args.proxy else "build"
        raise CliError(f"nothing built in {out} to flash: build it first "
                       f"(easylab {build} {args.file} --board {args.board} -o {out})")
    return _run(command, args.print)


def cmd_sim(args) -> int:
    args.simulation = True
    board, program, out = _board_and_program(args)
    try:
        command = board.simulator_command(out, program) + list(args.args)
    except (BuildError, BoardCannotRun) as err:
        raise CliError(str(err)) from None
    if not args.print and not Path(command[0]).is_file():
        raise CliError(f"no simulation build in {out}: build it first "
                       f"(easylab build {args.file} --board {args.board} --sim -o {out})")
    return _run(command, args.print)


def add_parsers(sub) -> None:
    p = sub.add_parser("boards", help="list the boards found",
                       description="List the boards found on the board path: --board-path folders, then "
                                   "EASYLAB_BOARD_PATH (folders separated by ':'), then the installed boards.")
    p.add_argument("--board-path", metavar="DIR", action="append", default=[], help="a folder of further boards")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--default-mcu", metavar="BOARD", help="print only this board's default MCU (empty if it has "
                                                          "no MCU choice)")
    p.set_defaults(func=cmd_boards)

    p = sub.add_parser("flash", help="burn a build into a board",
                       description="Run the board's programmer command on the build in -o DIR (default "
                                   "build/<model>/<board>/), printing it first; --print only prints it.")
    p.add_argument("file", metavar="FILE", help="model file (.elab) of the build")
    add_board_options(p)
    p.add_argument("--port", required=True, metavar="PORT", help="the board's serial port, e.g. /dev/ttyACM0")
    p.add_argument("--programmer", metavar="NAME", help="the programmer (default: the board's bootloader)")
    p.add_argument("--baud", type=int, metavar="N", help="the upload baud rate (default: the board's)")
    p.add_argument("-o", "--output", metavar="DIR", help="the build's folder")
    p.add_argument("--print", action="store_true", help="print the command, do not run it")
    p.add_argument("--proxy", action="store_true", help="flash the model's remote-execution proxy (easylab proxy; "
                                                       "default folder build/<model>/<board>-proxy/)")
    p.set_defaults(func=cmd_flash)

    p = sub.add_parser("sim", help="run a simulation build",
                       description="Run the board's simulator on the simulation build in -o DIR (easylab build "
                                   "--sim), its serial links on pseudo-terminals in DIR, printing the command "
                                   "first; further arguments go to the simulator (--stimulus, --trace, "
                                   "--duration, ...).")
    p.add_argument("file", metavar="FILE", help="model file (.elab) of the build")
    add_board_options(p)
    p.add_argument("-o", "--output", metavar="DIR", help="the build's folder")
    p.add_argument("--print", action="store_true", help="print the command, do not run it")
    p.add_argument("args", nargs="*", metavar="ARG", help="simulator arguments (after --)")
    p.set_defaults(func=cmd_sim)
