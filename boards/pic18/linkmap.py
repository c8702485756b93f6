"""gplink's map file: what a PIC18 build takes of program memory and RAM,
and where its symbols are (the simulator's RAM tables, `symbols`)."""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

_SECTION = re.compile(r"^\s*(\S+)\s+(code|romdata|udata|idata|udata_acs|idata_acs|udata_ovr|udata_shr)\s+"
                      r"0x([0-9a-fA-F]+)\s+(program|data)\s+0x([0-9a-fA-F]+)\s*$")
_SYMBOL = re.compile(r"^\s*(\S+)\s+0x([0-9a-fA-F]+)\s+(program|data)\s+(static|extern)\s+(\S+)\s*$")
SFR_START = 0xF80  # the special function registers of these parts (RAM ends below)
CONFIG_START = 0x200000  # ID locations, configuration words, device id: not program memory


@dataclass
class Section:
    name: str
    kind: str
    address: int
    location: str
    size: int


@dataclass
class LinkMap:
    sections: list[Section] = field(default_factory=list)
    symbols: dict[str, tuple[int, str, str]] = field(default_factory=dict)  # name -> (address, location, file)
    statics: dict[str, list[tuple[int, str]]] = field(default_factory=dict)  # data: name -> (address, file) each

    @property
    def flash(self) -> int:
        """Bytes of program memory (code, tables, initial values)."""
        return sum(s.size for s in self.sections if s.location == "program" and s.address < CONFIG_START)

    @property
    def ram(self) -> int:
        """Bytes of RAM: static data, sdcc's registers and the software stack."""
        return sum(s.size for s in self.sections if s.location == "data" and s.address < SFR_START)

    @property
    def stack(self) -> int:
        """Bytes of the software stack (the section holding `_stack`)."""
        return sum(s.size for s in self.sections if self._is_stack(s))

    def _is_stack(self, section: Section) -> bool:
        bottom = self.symbols.get("_stack")
        return section.location == "data" and bottom is not None and section.address == bottom[0]

    def ram_symbols(self) -> dict[str, int]:
        """C name -> RAM address of every external and static object."""
        return {name[1:]: addr for name, (addr, loc, _file) in self.symbols.items()
                if loc == "data" and name.startswith("_") and addr < SFR_START}

    def largest_ram(self, top: int = 6) -> list[tuple[int, str, str]]:
        """(bytes, C name, file) of the biggest objects in RAM: an object
        ends where the next symbol of its section begins. A static object
        renamed for sdcc (sdcc_quirks: NAME__UNIT) shows its own name."""
        symbols = sorted((addr, name[1:], Path(f).stem.removesuffix(".sdcc"))
                         for name, (addr, loc, f) in self.symbols.items()
                         if loc == "data" and name.startswith("_") and addr < SFR_START)
        found = []
        for s in self.sections:
            if s.location != "data" or s.address >= SFR_START or self._is_stack(s):
                continue
            inside = [sym for sym in symbols if s.address <= sym[0] < s.address + s.size]
            for (addr, name, src), nxt in zip(inside, inside[1:] + [(s.address + s.size, "", "")]):
                found.append((nxt[0] - addr, name.removesuffix(f"__{src}"), src))
        return sorted(found, reverse=True)[:top]


def read_map(path: Path) -> LinkMap:
    m = LinkMap()
    for line in path.read_text(encoding="latin-1").splitlines():
        s = _SECTION.match(line)
        if s:
            m.sections.append(Section(s.group(1), s.group(2), int(s.group(3), 16), s.group(4), int(s.group(5), 16)))
            continue
        y = _SYMBOL.match(line)
        if y:
            name, addr, loc, storage, src = y.groups()
            if storage == "extern" or name not in m.symbols:
                m.symbols[name] = (int(addr, 16), loc, src)
            if storage == "static" and loc == "data" and (int(addr, 16), src) not in m.statics.get(name, []):
                m.statics.setdefault(name, []).append((int(addr, 16), src))
    return m
