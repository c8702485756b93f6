"""Each node of a distributed model against its board: the boards' own
resource and driver checks, run on the node's program
(docs/distribution.md)."""

from __future__ import annotations

from ..core.errors import BuildError
from ..ir.program import Program
from ..ir.split import split
from .registry import load_board


def dds_problem(board, program: Program) -> str | None:
    """Why a node's program with DDS exports or channel ends cannot go on
    ``board`` (one whose board.toml lacks ``dds = true``), else None."""
    if not (program.exports or program.dds_channels) or board.description.raw.get("dds", False):
        return None
    return (f"a DDS peer with exports or channels needs a board with DDS (board.toml: dds = true), and board "
            f"'{board.name}' has none: put them on a PC node")


def threads_problem(board, cores: int) -> str | None:
    """Why ``board`` cannot run on ``cores`` cores (its board.toml lacks
    ``threads = true``), else None."""
    if cores <= 1 or board.description.raw.get("threads", False):
        return None
    return (f"board '{board.name}' runs on one core: {cores} cores need a board that runs threads (board.toml: "
            f"threads = true; the host board; docs/multicore.md)")


def node_problems(program: Program, board_path: list[str] | tuple[str, ...] = ()) -> list[str]:
    """What keeps each node's program off its board (a resource its part
    lacks, a pin claimed twice, a driver the board has not), one message
    per node that does not fit, naming the node and its board; empty when
    every node fits."""
    problems = []
    for name, node in split(program).items():
        where = f"node '{name}' (board {node.node.board}{f', {node.node.mcu}' if node.node.mcu else ''})"
        try:
            board = load_board(node.node.board, board_path)
            dds = dds_problem(board, node.program)
            if dds:
                raise BuildError(dds)
            threads = threads_problem(board, node.node.cores)
            if threads:
                raise BuildError(threads)
            board.configure(node.node.mcu).check(node.program)
        except BuildError as err:
            problems.append(f"{where}: {err}")
    return problems
