"""``easylab build``: generate C for a board and compile it with the board's
toolchain into build/<model>/<board>/.

The steps are the same for every board; what differs is the board's, behind
the board contract (board/contract.py): it checks the model's resource
claims, adds its own generated files, compiles, reports sizes and builds a
simulator.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from .board.cbuild import write_files
from .board.contract import Board, CompileOptions, Compiled
from .board.registry import load_board
from .codegen.render import render
from .core.errors import BuildError
from .ir.program import Program

__all__ = ["BuildError", "BuildResult", "build", "build_nodes", "generate"]


@dataclass
class BuildResult:
    out_dir: Path
    board: Board
    compiled: Compiled
    sources: list[Path]  # the generated files
    notes: list[str] = field(default_factory=list)  # printed before the path (sizes, simulator)
    simulator: Path | None = None  # the simulator of a simulation build (--sim)

    @property
    def executable(self) -> Path:
        return self.compiled.executable


def generate(program: Program, board: Board, out_dir: Path, release: bool = False,
             checked: object = None, extra_files: dict[str, str] | None = None, plan=None,
             profile: bool = False) -> list[Path]:
    """Write the generated files (model.c, the interfaces' tables and maps,
    the board's own files, ``extra_files``: a node's link; ``plan``: a
    multi-core plan; ``profile``: every firing timed); returns their
    paths."""
    files = render(program, board, release=release, plan=plan, profile=profile)
    files.update(extra_files or {})
    files.update(board.produce(program, checked, release))
    return write_files(out_dir, files)


def build(program: Program, board_name: str, out_dir: Path, extra_cflags: list[str] | None = None,
          cc: str | None = None, release: bool = False, mcu: str | None = None, sim: bool = False,
          schedule: str | None = None, board_path: list[str] | tuple[str, ...] = (),
          check: bool = False, extra_files: dict[str, str] | None = None, cores: int = 1,
          always_parallel: bool = False, profile: bool = False) -> BuildResult:
    """Generate and compile ``program`` for a board (found on the board
    path: ``board_path``, EASYLAB_BOARD_PATH, the installation). A release
    build has no debug interface; ``sim`` adds the board's simulator;
    ``check`` runs the board's further checks of the C. ``cores`` > 1: a
    multi-core build where the plan says it pays (``always_parallel``:
    whatever it says), on a board that runs threads; ``profile``: a
    profiling build of the host board (docs/multicore.md)."""
    if program.deployment is not None:
        raise BuildError(f"model '{program.name}' has nodes: it is built node by node (build_nodes, "
                         "docs/distribution.md)")
    board = load_board(board_name, board_path).configure(mcu, sim)
    plan, plan_notes = _multicore_plan(program, board, cores, always_parallel)
    checked = board.check(program)
    generated = generate(program, board, out_dir, release, checked, extra_files, plan, profile)
    options = CompileOptions(release, tuple(extra_cflags or ()), cc, schedule, check, threads=plan is not None,
                             profile=profile)
    compiled = board.compile(program, checked, out_dir, generated, options)
    result = BuildResult(out_dir, board, compiled, generated, plan_notes + list(compiled.size.lines if compiled.size else []))
    result.notes += compiled.notes
    if sim:
        simulator = board.build_simulator(program, checked, out_dir, compiled)
        result.simulator = simulator.program
        result.notes += simulator.notes + [f"simulator: {simulator.program}"]
    return result


def _multicore_plan(program: Program, board: Board, cores: int, always: bool):
    """(the plan to print, or None for a single-core build; the notes that
    say what was chosen)."""
    if cores <= 1:
        return None, []
    from .board.nodes import threads_problem

    problem = threads_problem(board, cores)
    if problem:
        raise BuildError(problem)
    from .ir.multicore import plan as multicore_plan

    found = multicore_plan(program, cores, always=always)
    return (found if found.parallel else None), found.notes()


def build_nodes(program: Program, out_dir: Path, extra_cflags: list[str] | None = None, release: bool = False,
                schedule: str | None = None, board_path: list[str] | tuple[str, ...] = (),
                check: bool = False) -> dict[str, BuildResult]:
    """Build each node of a distributed program on its own board into
    ``out_dir/<node>/`` (an MCU node with its board's simulator, for
    ``easylab launch``); the builds by node name (docs/distribution.md)."""
    from .board.nodes import dds_problem
    from .codegen.link import link_defines, link_files
    from .ir.split import split

    if program.deployment is None:
        raise BuildError(f"model '{program.name}' has no nodes: build it for one board")
    nodes = split(program)
    for name, node in nodes.items():  # before any build
        dds = dds_problem(load_board(node.node.board, board_path), node.program)
        if dds:
            raise BuildError(f"node '{name}': {dds}")
    built = {}
    for name, node in nodes.items():
        board = load_board(node.node.board, board_path)
        cflags = [*(extra_cflags or ()), *link_defines(node)]
        built[name] = build(node.program, node.node.board, out_dir / name, cflags, None, release,
                            node.node.mcu, sim=board.has_simulator, schedule=schedule,
                            board_path=board_path, check=check, extra_files=link_files(node),
                            cores=node.node.cores)
    return built
