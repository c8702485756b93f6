"""Every banked RAM access of a linked PIC18 program checked against the
bank select register (BSR) it runs under.

An instruction that names a RAM object outside the access bank (`MOVF _x,
W, B`) reaches the bank BSR holds, which `BANKSEL _x` (MOVLB) sets. sdcc's
pic16 port decides where BSR is set while compiling, before gplink has
placed anything, and its bank optimisations (`--obanksel`, the pCode
optimiser) reason about banks they do not know: a missing or stale BANKSEL
reads or writes the same offset in another bank (std's Counter tested its
input under the bank of the previous store). Once linked, every address
is known, so the whole program can be checked.

The check follows BSR through each function of sdcc's assembly: a BANKSEL
or MOVLB sets it; a call, a return or inline assembly leave it unknown; a
label joins what every jump to it and the fall-through bring (different
banks: unknown); a skip goes on at the next two instructions. A banked
access whose bank BSR does not surely hold is a fault: `check` lists them,
and the build recompiles the file with the bank optimisations off
(sdcc.py), which must leave none.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from .linkmap import LinkMap

_LABEL = re.compile(r"^([A-Za-z_.$?][\w.$?]*):")
_INSN = re.compile(r"^\t([A-Za-z]+)\b\s*(.*)$")
_OPERAND = re.compile(r"^\(?\s*([A-Za-z_][\w]*)\s*(?:\+\s*(0x[0-9a-fA-F]+|\d+))?\s*\)?$")
_BRANCHES = {"BRA", "GOTO", "BZ", "BNZ", "BC", "BNC", "BN", "BNN", "BOV", "BNOV"}
_UNCONDITIONAL = {"BRA", "GOTO", "RETURN", "RETFIE", "RETLW", "RESET"}
_SKIPS = {"BTFSC", "BTFSS", "CPFSEQ", "CPFSGT", "CPFSLT", "TSTFSZ", "INCFSZ", "DECFSZ", "INFSNZ", "DCFSNZ"}
_UNKNOWN = -1  # a bank number BSR may not hold
_UNSET = -2  # not reached yet


@dataclass(frozen=True)
class Fault:
    """A banked access whose bank BSR does not surely hold."""

    file: str
    line: int
    text: str
    needs: int
    bsr: int  # -1: unknown

    def __str__(self) -> str:
        held = "unknown" if self.bsr < 0 else f"bank {self.bsr}"
        return f"{self.file}:{self.line}: {self.text.strip()} needs bank {self.needs}, BSR holds {held}"


@dataclass
class _Insn:
    line: int
    op: str
    args: list[str]
    text: str
    labels: list[str]


def _parse(asm: str) -> list[list[_Insn]]:
    """The code of each section: its instructions with the labels before
    them (inline assembly and data directives end nothing: they are kept
    as instructions of their own)."""
    sections: list[list[_Insn]] = []
    current: list[_Insn] | None = None
    labels: list[str] = []
    for number, raw in enumerate(asm.split("\n"), 1):
        line = raw.split(";", 1)[0].rstrip()
        if not line.strip():
            continue
        if not line.startswith("\t") and not _LABEL.match(line):
            words = line.split()
            current = [] if len(words) >= 2 and words[1] == "code" else None
            if current is not None:
                sections.append(current)
            labels = []
            continue
        if current is None:
            continue
        m = _LABEL.match(line)
        if m:
            labels.append(m.group(1))
            line = line[m.end():]
            if not line.strip():
                continue
            line = "\t" + line.strip()
        m = _INSN.match(line)
        if not m:
            continue
        args = [a.strip() for a in m.group(2).split(",")] if m.group(2).strip() else []
        current.append(_Insn(number, m.group(1).upper(), args, raw, labels))
        labels = []
    return sections


class _Banks:
    """Addresses of the program's RAM symbols (the link map), as sdcc names
    them in one file."""

    def __init__(self, lmap: LinkMap, asm_file: Path):
        self.lmap, self.file = lmap, str(asm_file)

    def bank(self, operand: str) -> int | None:
        m = _OPERAND.match(operand)
        if not m:
            return None
        entry = self.lmap.symbols.get(m.group(1))
        statics = [s for s in self.lmap.statics.get(m.group(1), []) if s[1] == self.file]
        address = statics[0][0] if statics else entry[0] if entry and entry[1] == "data" else None
        if address is None:
            return None
        return (address + int(m.group(2) or "0", 0)) >> 8


def _successors(code: list[_Insn], k: int, where: dict[str, int]) -> list[int]:
    insn = code[k]
    out = []
    if insn.op in _BRANCHES and insn.args and insn.args[0] in where:
        out.append(where[insn.args[0]])
    if insn.op not in _UNCONDITIONAL:
        out.append(k + 1)
    if insn.op in _SKIPS:
        out.append(k + 2)
    return [s for s in out if s < len(code)]


def _after(insn: _Insn, bsr: int, banks: _Banks) -> int:
    if insn.op == "BANKSEL" and insn.args:
        b = banks.bank(insn.args[0])
        return _UNKNOWN if b is None else b
    if insn.op == "MOVLB" and insn.args:
        try:
            return int(insn.args[0], 0)
        except ValueError:
            return _UNKNOWN
    if insn.op in ("CALL", "RCALL", "DB", "DW", "DATA"):
        return _UNKNOWN
    if insn.args and insn.args[0].upper() in ("BSR", "_BSR"):
        return _UNKNOWN
    return bsr


def check(asm: str, asm_file: Path, lmap: LinkMap) -> list[Fault]:
    """The banked accesses of one assembly file that may run under another bank."""
    banks = _Banks(lmap, asm_file)
    faults: list[Fault] = []
    for code in _parse(asm):
        where = {label: k for k, insn in enumerate(code) for label in insn.labels}
        targets = {code[k].args[0] for k in range(len(code))
                   if code[k].op in _BRANCHES and code[k].args and code[k].args[0] in where}
        state = [_UNSET] * len(code)
        for k, insn in enumerate(code):  # entries: function labels, labels reached from elsewhere
            if k == 0 or any(label not in targets for label in insn.labels):
                state[k] = _UNKNOWN
        work = [k for k in range(len(code)) if state[k] != _UNSET]
        while work:
            k = work.pop()
            out = _after(code[k], state[k], banks)
            for s in _successors(code, k, where):
                joined = out if state[s] == _UNSET else state[s] if state[s] == out else _UNKNOWN
                if joined != state[s]:
                    state[s] = joined
                    work.append(s)
        for k, insn in enumerate(code):
            if state[k] == _UNSET or not insn.args or insn.args[-1] != "B" or insn.op == "BANKSEL":
                continue
            needs = banks.bank(insn.args[0])
            if needs is not None and needs != state[k]:
                faults.append(Fault(asm_file.name, insn.line, insn.text, needs, state[k]))
    return faults
