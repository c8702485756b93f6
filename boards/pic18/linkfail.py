"""What gplink could not place: its message, the section it names, how big
that section is and what is in it.

gplink fails a program it cannot place with one line per section, e.g.
``error: No target memory available for section "udata_model_gen_sdcc_34".``
The section's size, its memory (program memory or RAM) and its symbols
are in the object that defines it; gputils' gpvo reads them.
"""

from __future__ import annotations

import re
import subprocess
from dataclasses import dataclass, field
from pathlib import Path

from .sdcc_quirks import BANK_BYTES  # a RAM section must fit within one bank

_NO_MEMORY = re.compile(r'^(?:error: )?No target memory available for section "(?P<section>[^"]+)"\.?\s*$')
_HEADER_NAME = re.compile(r"^Name\s+(\S+)\s*$")
_HEADER_SIZE = re.compile(r"^Size of Section\s+(\d+)\s*$")
# gpvo -t: `0143 _el_df0_x_458752_175 udata_model_gen_sdcc_34 0  T_NULL DT_NON C_STAT 0`
_SYMBOL = re.compile(r"^[0-9a-fA-F]{4}\s+(?P<name>\S+)\s+(?P<section>\S+)\s+\S+\s+\S+\s+\S+\s+(?P<cls>C_\w+)\s")


@dataclass
class Unplaced:
    """A section gplink found no room for."""

    message: str  # gplink's own line (after "error: ")
    section: str
    size: int | None = None  # bytes; None when no object of the program defines it (a library's)
    memory: str = "RAM"  # "RAM" or "program memory"
    obj: Path | None = None
    symbols: list[str] = field(default_factory=list)  # the C names in it (sdcc's, without the '_')

    @property
    def source(self) -> str | None:
        """The C file the section comes from (``model.c`` for model_gen.o)."""
        return None if self.obj is None else self.obj.stem.removesuffix("_gen") + ".c"

    def describe(self) -> str:
        """gplink's message, then the section's memory, size and content."""
        text = f"gplink: error: {self.message}"
        if self.size is None:
            return text
        inside = ", ".join(self.symbols[:4]) + (", ..." if len(self.symbols) > 4 else "")
        return (f"{text}\nsection \"{self.section}\": {self.memory}, {self.size} bytes, "
                f"{inside + ' ' if inside else ''}in {self.source}")

    @property
    def larger_than_a_bank(self) -> bool:
        """A RAM section no bank can hold, however empty."""
        return self.memory == "RAM" and self.size is not None and self.size > BANK_BYTES


def unplaced_sections(error: str, objects: list[Path]) -> list[Unplaced]:
    """Every section gplink's ``error`` (its output) says it could not
    place, with what the program's ``objects`` say of it."""
    found = []
    for line in error.splitlines():
        m = _NO_MEMORY.match(line.strip())
        if m:
            found.append(Unplaced(line.strip().removeprefix("error: "), m.group("section")))
    wanted = {u.section: u for u in found}
    for obj in objects:
        if not wanted:
            break
        if not obj.is_file():
            continue
        for name, size, memory, symbols in _sections(obj):
            u = wanted.pop(name, None)
            if u is not None:
                u.size, u.memory, u.obj, u.symbols = size, memory, obj, symbols
    return found


def _sections(obj: Path) -> list[tuple[str, int, str, list[str]]]:
    """(name, size, memory, C symbols) of each section of an object, from gpvo."""
    try:
        headers = _gpvo("-s", obj)
        table = _gpvo("-t", obj)
    except (OSError, subprocess.SubprocessError):
        return []
    symbols: dict[str, list[str]] = {}
    for line in table.splitlines():
        s = _SYMBOL.match(line)
        # objects and functions (a static function's name is a label); not sdcc's own labels (_00105_DS_)
        if s and s.group("cls") in ("C_EXT", "C_STAT", "C_LABEL") and re.match(r"_[A-Za-z]", s.group("name")):
            symbols.setdefault(s.group("section"), []).append(s.group("name")[1:])
    sections = []
    name = size = None
    for line in headers.splitlines() + ["Section Header"]:
        if line.startswith("Section Header") and name is not None and size is not None:
            sections.append((name, size, memory, symbols.get(name, [])))
            name = size = None
        elif (m := _HEADER_NAME.match(line)) is not None:
            name, memory = m.group(1), "RAM"
        elif (m := _HEADER_SIZE.match(line)) is not None:
            size = int(m.group(1))
        elif line.strip() in ("Executable code.", "Initialized data for ROM."):
            memory = "program memory"
    return sections


def _gpvo(option: str, obj: Path) -> str:
    """gpvo's listing of an object: ``-s`` its section headers, ``-t`` its symbols."""
    return subprocess.run(["gpvo", option, str(obj)], capture_output=True, text=True, timeout=60,
                          stdin=subprocess.DEVNULL, check=True).stdout
