"""Each node of a distributed model against its board: the boards' own
resource and driver checks, run on the node's program
(docs/distribution.md)."""

from __future__ import annotations

from ..core.errors import BuildError
from ..ir.program import Program
from ..ir.split import split
from .registry import load_board


def node_problems(program: Program, board_path: list[str] | tuple[str, ...] = ()) -> list[str]:
    """What keeps each node's program off its board (a resource its part
    lacks, a pin claimed twice, a driver the board has not), one message
    per node that does not fit, naming the node and its board; empty when
    every node fits."""
    problems = []
    for name, node in split(program).items():
        where = f"node '{name}' (board {node.node.board}{f', {node.node.mcu}' if node.node.mcu else ''})"
        try:
            load_board(node.node.board, board_path).configure(node.node.mcu).check(node.program)
        except BuildError as err:
            problems.append(f"{where}: {err}")
    return problems
