"""Helpers of the AVR board's tests: the CLI, cross builds, the simavr
harness, host builds to compare with.

Everything goes through the ``easylab`` command line as a user would run
it (``python -m easylab`` with this interpreter and the inherited
environment), then through the built programs. CI has avr-gcc, avr-libc,
simavr and libsimavr: nothing here is skipped.
"""

from __future__ import annotations

from pathlib import Path

from firmware_builds import (EXAMPLE_NAMES, EXAMPLES, ROOT, Built, build, cli, run_program,  # noqa: F401
                             stimulus_of)

HERE = Path(__file__).resolve().parent


def debug_client_class():
    """easylab.host_tools' DebugClient (installed, or from this source tree
    where `easylab` is generator/ alone)."""
    import easylab

    try:
        import easylab.host_tools  # noqa: F401
    except ImportError:
        easylab.__path__.append(str(ROOT))
    from easylab.host_tools.debug_protocol import DebugClient

    return DebugClient


def avr_build(model: Path | str, out: Path, *args: str, ok: bool = True) -> Built:
    """``easylab build MODEL --board avr ARGS -o OUT``."""
    built = build(model, "avr", out, *args, ok=ok)
    if ok:
        assert built.elf.suffix == ".elf" and built.elf.is_file(), built.proc.stdout
    return built


def host_build(model: Path | str, out: Path) -> Path:
    return build(model, "host", out).executable


run = run_program  # a built program with ARGS (firmware_builds)
