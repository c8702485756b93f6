"""The text of a resource claim (docs/language.md, "Devices"): its kind
and index (``pin["PB5"]``, ``uart[1]``, ``i2c[0]``) and its place on a
bus (``addr 0x48``, ``cs "PB2"``). Shared by the resources check and the
rendering of handler files (a chip select's pin)."""

from __future__ import annotations

import re

_CLAIM = re.compile(r'^([A-Za-z_][A-Za-z0-9_]*)\[(?:"([^"]*)"|(\d+))\](?: (addr|cs) (?:"([^"]*)"|(0x[0-9a-fA-F]+|\d+)))?$')


def parse_claim(text: str) -> tuple[str, object] | None:
    """``pin["PB5"]`` -> ("pin", "PB5"); ``uart[1]`` -> ("uart", 1);
    ``i2c[0] addr 0x48`` -> ("i2c", 0) (its place: :func:`parse_select`)."""
    m = _CLAIM.match(text.strip())
    if m is None:
        return None
    return m.group(1), (m.group(2) if m.group(2) is not None else int(m.group(3)))


def parse_select(text: str) -> tuple[str, object] | None:
    """A claim's place on a bus: ``i2c[0] addr 0x48`` -> ("addr", 0x48),
    ``spi[0] cs "PB2"`` -> ("cs", "PB2"); None for a claim without one."""
    m = _CLAIM.match(text.strip())
    if m is None or m.group(4) is None:
        return None
    return m.group(4), (m.group(5) if m.group(5) is not None else int(m.group(6), 0))
