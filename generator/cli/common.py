"""What the commands of ``easylab`` share: the error they report as one
line, exit statuses, reading a model, the board options."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

EXIT_OK, EXIT_MODEL_ERROR, EXIT_USAGE = 0, 1, 2


class CliError(Exception):
    """A failure to report as one line, ``easylab: error: ...``."""


def check_model(path: str):
    """The front end's result for a model file; an unreadable file is a
    CliError."""
    from ..pipeline import check_file

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


def lower_model(path: str, schedule: str | None = None):
    """The IR of a model file; a bad model prints its errors and exits 1."""
    from ..pipeline import lower_file

    try:
        program, result = lower_file(path, schedule=schedule)
    except FileNotFoundError:
        raise CliError(f"{path}: no such file") from None
    except (IsADirectoryError, UnicodeDecodeError):
        raise CliError(f"{path}: not a model file") from None
    if program is None:
        print(result.report(), file=sys.stderr)
        raise SystemExit(EXIT_MODEL_ERROR)
    return program


def default_out_dir(program, board: str) -> Path:
    """Where a build goes without -o: build/<model>/<board>/."""
    return Path("build") / program.name / board


DEFAULT_BOARD = "host"


def add_board_options(p: argparse.ArgumentParser,
                      mcu_help: str = "the board's MCU (default: the board's own)",
                      board_default: str | None = DEFAULT_BOARD, board_help: str = "") -> None:
    """--board, --mcu and --board-path, as build, flash and sim take them.
    With ``board_default`` None a command tells an absent --board (None)
    from ``--board host`` and takes DEFAULT_BOARD itself."""
    p.add_argument("--board", default=board_default,
                   help=f"target board (default: {DEFAULT_BOARD}{board_help}; `easylab boards` lists them)")
    p.add_argument("--mcu", metavar="MCU", help=mcu_help)
    p.add_argument("--board-path", metavar="DIR", action="append", default=[],
                   help="a folder of further boards (searched before EASYLAB_BOARD_PATH and the installed "
                        "boards; may be repeated)")


def report_built(built) -> int:
    """What a build prints: its notes, then the path of the program built
    on the last line."""
    for note in built.notes:
        print(note)
    print(built.executable)
    return EXIT_OK


def cores_arg(text: str) -> int:
    """--cores N: 1 to 64."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number of cores: {text!r}") from None
    if not 1 <= value <= 64:
        raise argparse.ArgumentTypeError(f"the number of cores must be 1 to 64, not {value}")
    return value
