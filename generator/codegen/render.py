"""All the C a build generates, in one call: model.c and what each
interface adds beside it (its tables and maps) and inside it (its start
and poll glue). Boards add their own files through the board contract.

The interfaces are the producers below, in order: the debug interface
(docs/protocol.md) and the service interface (docs/service.md).
"""

from __future__ import annotations

import functools
from pathlib import Path
from typing import Protocol

import jinja2

from ..core.paths import templates_dir
from ..ir.program import Device, Program
from . import debug, service
from .c_model import CModel, build_view
from .c_syntax import c_comment, c_string, ident


class Target(Protocol):
    """What the C generators need of a board (a part of the board
    contract): its name, how a device's handlers are called, and the size
    of its non-volatile store."""

    name: str

    @property
    def nv_size(self) -> int | None: ...

    def device_call(self, device: Device, handler: str) -> str: ...


# Further outputs beside model.c: each producer takes (program, target,
# jinja environment, view, release) and returns {file name: text}; .c files
# are compiled with the firmware.
PRODUCERS = (debug.produce, service.produce)

# The interfaces' glue in model.c: each hook takes (program, release) and
# returns (boot statements, idle statements) for el_gen_interfaces_boot and
# el_gen_interfaces_poll.
INTERFACE_HOOKS = (debug.interface_hook, service.interface_hook)


def environment(template_dir: Path | None = None) -> jinja2.Environment:
    """The Jinja2 environment of the C templates: one per folder, so that
    each template is compiled once per process (local execution renders
    the actor template once per actor specialisation, hundreds per model).
    Shared: callers must not change it."""
    return _environment(str(template_dir or templates_dir()))


@functools.lru_cache(maxsize=None)
def _environment(template_dir: str) -> jinja2.Environment:
    env = jinja2.Environment(loader=jinja2.FileSystemLoader(template_dir),
                             undefined=jinja2.StrictUndefined, trim_blocks=True, lstrip_blocks=True,
                             keep_trailing_newline=True,
                             # compiled templates kept between runs (checked against their source)
                             bytecode_cache=jinja2.FileSystemBytecodeCache())
    env.filters["c_ident"] = ident
    # Model strings (titles, names of files) in comments and literals.
    env.filters["c_comment"] = c_comment
    env.filters["c_string"] = c_string
    return env


def render(program: Program, board: Target, template_dir: Path | None = None,
           release: bool = False, plan=None, profile: bool = False) -> dict[str, str]:
    """The generated files: {file name: text}. Deterministic: the same
    program gives byte-identical files. ``plan``: a multi-core plan
    (ir/multicore.py); one that runs nothing in parallel changes
    nothing. ``profile``: a profiling build (cli/profile.py)."""
    view = _view_with_interfaces(program, board, release, plan=plan, profile=profile)
    env = environment(template_dir)
    files = {"model.c": env.get_template("model.c.j2").render(m=view)}
    for produce in PRODUCERS:
        files.update(produce(program, board, env, view, release))
    return files


def render_interfaces(program: Program, board: Target, template_dir: Path | None = None) -> dict[str, str]:
    """The generated files of local execution's interfaces library (a debug
    build): interp_interfaces.c, the model's storage and interface glue,
    in place of model.c, and what the producers write beside it (debug and
    service tables and maps)."""
    view = _view_with_interfaces(program, board, False, library=True)
    env = environment(template_dir)
    files = {"interp_interfaces.c": env.get_template("interp_interfaces.c.j2").render(m=view)}
    for produce in PRODUCERS:
        files.update(produce(program, board, env, view, False))
    return files


def _view_with_interfaces(program: Program, board: Target, release: bool, library: bool = False,
                          plan=None, profile: bool = False) -> CModel:
    probes = not release and not library and debug.has_debug_interface(program)
    view = build_view(program, board, library, probes, plan, profile)
    for hook in INTERFACE_HOOKS:
        boot, poll = hook(program, release)
        view.interface_boot.extend(boot)
        view.interface_poll.extend(poll)
    return view
