"""The debug protocol's numbers, read from their one source,
runtime_c/el_debug_protocol.h (docs/protocol.md): the checker bounds a
model's debug settings by them, the generator and the host tools speak
them."""

from __future__ import annotations

import functools
import re
from pathlib import Path
from types import SimpleNamespace

from .paths import runtime_dir


_DEFINE = re.compile(r"^\s*#\s*define\s+EL_DBG_(\w+)\s+\(?(0[xX][0-9A-Fa-f]+|\d+)[uUlL]*\)?\s*(?:/\*.*)?$")


def protocol_header_path() -> Path:
    """runtime_c/el_debug_protocol.h of this installation: the one source of
    the debug protocol's numbers (the same folder the C build compiles
    from)."""
    return runtime_dir() / "el_debug_protocol.h"


def parse_protocol_header(text: str) -> dict[str, int]:
    """``{NAME: value}`` of every ``#define EL_DBG_NAME <integer>`` line."""
    values: dict[str, int] = {}
    for line in text.splitlines():
        m = _DEFINE.match(line)
        if m:
            values[m.group(1)] = int(m.group(2), 0)
    return values


@functools.lru_cache(maxsize=None)
def protocol_constants() -> SimpleNamespace:
    """The protocol's constants by their C names without ``EL_DBG_``."""
    return SimpleNamespace(**parse_protocol_header(protocol_header_path().read_text(encoding="utf-8")))


