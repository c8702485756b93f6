"""sdcc's register saves, frame set-up and argument loads, shared by
every function.

sdcc's pic16 port saves each of its registers r0x00, r0x01, ... that a
function uses when the function begins (`MOVFF r0xNN, POSTDEC1`, 4 bytes)
and restores them before it returns (`MOVFF PREINC1, r0xNN`): 8 bytes per
register per function. A function with parameters also pushes and sets
the frame pointer FSR2 (16 bytes), pops it at its exit (8) and loads each
byte of its arguments from FSR2 + 3 up into r0x00 up (6 bytes each).
Together over a quarter of a debug build's program memory. This pass
rewrites each function of sdcc's assembly:

- the saves of r0x00 .. r0x(k-1) (after the frame pointer's set-up, if
  any) as `MOVLW k` and a call of a routine that does the same
  (_el_pic18_save_regs, or _el_pic18_enter with the frame pointer first);
- the argument loads as `MOVLW n` and a call of _el_pic18_load_args;
- each exit (the restores, the frame pointer's pops, RETURN) as a GOTO to
  entry k of a chain of restores that ends in RETURN (or a CALL of it when
  something else follows the restores).

The software stack holds the same bytes in the same places as before (a
function may save one or two registers it does not use, which changes
nothing). The entry routines use W, FSR0 and PRODL, which hold nothing
when a function begins (sdcc passes arguments on the software stack);
_el_pic18_load_args leaves W as sdcc's own loads did. The restores touch
neither W, PRODL, PRODH nor FSR0L, which carry the returned value, nor
STATUS. Interrupt handlers (RETFIE) keep their own code, and anything not
in the forms above is left as sdcc wrote it.

The routines are an assembly module of each link (``routines``), the
chains as long as the longest restores the build's files call.
"""

from __future__ import annotations

import re

SAVE = "_el_pic18_save_regs"  # W registers from r0x00 up
ENTER = "_el_pic18_enter"  # the frame pointer's push and setting, then SAVE (W may be 0)
LEAVE = "_el_pic18_leave_"  # + k: pop k registers and return
LEAVE_FRAME = "_el_pic18_leave_frame_"  # + k: pop k registers and the frame pointer, return
LOAD_ARGS = "_el_pic18_load_args"  # W bytes of arguments into r0x00 up
MIN_REGISTERS = 2  # without a frame, fewer cost as much as the call
MAX_GAPS = 2  # registers saved that the function does not use
MODULE = "el_pic18_saves"

_SAVE_LINE = re.compile(r"\tMOVFF\tr0x([0-9a-f]{2}), POSTDEC1\s*$")
_RESTORE_LINE = re.compile(r"\tMOVFF\tPREINC1, r0x([0-9a-f]{2})\s*$")
_FRAME = ("\tMOVFF\tFSR2H, POSTDEC1", "\tMOVFF\tFSR2L, POSTDEC1", "\tMOVFF\tFSR1H, FSR2H",
          "\tMOVFF\tFSR1L, FSR2L")
_UNFRAME = ("\tMOVFF\tPREINC1, FSR2L", "\tMOVFF\tPREINC1, FSR2H")
_SECTION = re.compile(r"^S_\w+\s+code\b")  # sdcc gives each function its own code section
_USED = re.compile(r"\t(?:CALL|GOTO)\t(_el_pic18_(?:save_regs|enter|load_args|leave_frame_\d+|leave_\d+))\b")
_FIRST_ARG = 3  # FSR2 + 3: above the frame pointer sdcc pushed


def _code(line: str) -> str:
    """The instruction of a line without its comment; '' for none."""
    return line.split(";", 1)[0].rstrip()


def _next_code(lines: list[str], at: int) -> int:
    """The first line from ``at`` with an instruction or a label."""
    while at < len(lines) and not _code(lines[at]):
        at += 1
    return at


def _run(lines: list[str], at: int, pattern: re.Pattern) -> list[int]:
    """The registers the lines from ``at`` save (or restore), in order."""
    regs = []
    while at + len(regs) < len(lines):
        m = pattern.match(lines[at + len(regs)])
        if not m:
            break
        regs.append(int(m.group(1), 16))
    return regs


def _saved(regs: list[int]) -> int:
    """How many registers from r0x00 up the shared routines save for a
    function whose own saves are ``regs`` (0: not shared). sdcc saves the
    registers a function uses in ascending order, sometimes with one left
    out: saving such an unused register too changes nothing but a byte of
    the stack, so a few gaps are filled."""
    if not regs or regs != sorted(set(regs)) or regs[-1] + 1 - len(regs) > MAX_GAPS:
        return 0
    return regs[-1] + 1


def _exit(lines: list[str], at: int, regs: list[int], k: int, frame: bool) -> tuple[int, list[str]] | None:
    """The exit whose restores begin at line ``at`` (of ``regs``, the
    prologue's saves; k registers shared): where it ends and what replaces
    it; None when it is not the prologue's mirror."""
    if regs and _run(lines, at, _RESTORE_LINE) != regs[::-1]:
        return None
    n = at + len(regs)
    if frame:
        a = _next_code(lines, n)
        b = _next_code(lines, a + 1)
        if a < len(lines) and b < len(lines) and (_code(lines[a]), _code(lines[b])) == _UNFRAME:
            r = _next_code(lines, b + 1)
            if r < len(lines) and _code(lines[r]) == "\tRETURN":
                return r + 1, [f"\tGOTO\t{LEAVE_FRAME}{k}"]
        # the frame pointer's pops stay as they are
        return (n, [f"\tCALL\t{LEAVE}{k}"]) if k else None
    r = _next_code(lines, n)
    if r < len(lines) and _code(lines[r]) == "\tRETURN":
        return r + 1, [f"\tGOTO\t{LEAVE}{k}"]
    return n, [f"\tCALL\t{LEAVE}{k}"]


def _arguments(lines: list[str], at: int) -> int:
    """How many argument bytes the lines from ``at`` load into r0x00 up,
    the first from FSR2 + 3 (`MOVLW 0x03`, `MOVFF PLUSW2, r0x00`, ...)."""
    n = 0
    while at + 2 * n + 1 < len(lines) and lines[at + 2 * n].rstrip() == f"\tMOVLW\t0x{_FIRST_ARG + n:02x}" \
            and lines[at + 2 * n + 1].rstrip() == f"\tMOVFF\tPLUSW2, r0x{n:02x}":
        n += 1
    return n


def _function(lines: list[str]) -> list[str]:
    """One function's lines (its section, then its label), its saves
    shared."""
    if len(lines) < 2 or not lines[1].endswith(":") or any(_code(l) == "\tRETFIE" for l in lines):
        return lines
    at = _next_code(lines, 2)
    frame = tuple(_code(lines[n]) if n < len(lines) else "" for n in range(at, at + 4)) == _FRAME
    saves_at = _next_code(lines, at + 4) if frame else at
    regs = _run(lines, saves_at, _SAVE_LINE)
    k = _saved(regs)
    if regs and k == 0 or not frame and k < MIN_REGISTERS:
        return lines
    first = _UNFRAME[0] if k == 0 else None
    exits = []
    for n in range(saves_at + len(regs), len(lines)):
        starts = _code(lines[n]) == first if first else \
            (_RESTORE_LINE.match(lines[n]) and not _RESTORE_LINE.match(lines[n - 1]))
        if starts:
            done = _exit(lines, n, regs, k, frame)
            if done is None:
                return lines  # not the saves' mirror: left as sdcc wrote it
            exits.append((n, *done))
    if not exits:
        return lines
    out = lines[:at] + [f"\tMOVLW\t0x{k:02x}", f"\tCALL\t{ENTER if frame else SAVE}"]
    n = saves_at + len(regs)
    args = _arguments(lines, n) if frame else 0
    if args >= 2:
        out += [f"\tMOVLW\t0x{args:02x}", f"\tCALL\t{LOAD_ARGS}"]
        n += 2 * args
    for begin, end, replacement in exits:
        out += lines[n:begin] + replacement
        n = end
    return out + lines[n:]


def share_saves(text: str) -> str:
    """sdcc's assembly of one file with each function's register saves and
    restores calling the shared routines (declared extern at the top)."""
    lines = text.split("\n")
    starts = [n for n, l in enumerate(lines) if _SECTION.match(l)] + [len(lines)]
    out = lines[:starts[0]]
    for a, b in zip(starts, starts[1:]):
        out += _function(lines[a:b])
    used = sorted(set(_USED.findall("\n".join(out))))
    if not used:
        return text
    first = next(n for n, l in enumerate(out) if l.startswith("\tradix"))
    return "\n".join(out[:first + 1] + [f"\textern\t{name}" for name in used] + out[first + 1:])


def longest_restores(texts: list[str]) -> tuple[int, int]:
    """The most registers an exit of these files pops without and with the
    frame pointer (-1: no such exit)."""
    plain = frame = -1
    for t in texts:
        for name in _USED.findall(t):
            if name.startswith(LEAVE_FRAME):
                frame = max(frame, int(name[len(LEAVE_FRAME):]))
            elif name.startswith(LEAVE):
                plain = max(plain, int(name[len(LEAVE):]))
    return plain, frame


def routines(device: str, plain: int, frame: int) -> str:
    """The assembly module of the shared saving routines and the chains of
    exits: up to ``plain`` registers without the frame pointer, up to
    ``frame`` with it (-1: no chain)."""
    registers = max(plain, frame, 1)
    regs = [f"r0x{k:02x}" for k in range(registers)]
    chain_plain = [line for k in range(plain, 0, -1) for line in (f"{LEAVE}{k}:", f"\tMOVFF\tPREINC1, {regs[k - 1]}")]
    chain_frame = [line for k in range(frame, 0, -1)
                   for line in (f"{LEAVE_FRAME}{k}:", f"\tMOVFF\tPREINC1, {regs[k - 1]}")]
    names = [SAVE, ENTER, LOAD_ARGS, *(f"{LEAVE}{k}" for k in range(1, plain + 1)),
             *(f"{LEAVE_FRAME}{k}" for k in range(0, frame + 1))]
    return "\n".join([
        "; sdcc's register saves and restores, shared (boards/pic18/saves.py). Do not edit.",
        f"\tlist\tp={device}", "\tradix\tdec",
        "WREG\tequ\t0xfe8", "POSTINC0\tequ\t0xfee", "POSTDEC1\tequ\t0xfe5", "PREINC1\tequ\t0xfe4",
        "FSR1L\tequ\t0xfe1", "FSR1H\tequ\t0xfe2", "FSR2L\tequ\t0xfd9", "FSR2H\tequ\t0xfda",
        "PLUSW2\tequ\t0xfdb", "PRODL\tequ\t0xff3",
        *(f"\tglobal\t{name}" for name in names),
        # sdcc's registers: the overlay every file of the build shares
        ".registers\tudata_ovr\t0x0000", *(f"{r}\tres\t1" for r in regs),
        f"S_{MODULE}\tcode",
        # the frame pointer as sdcc's functions set it, then W registers
        f"{ENTER}:", *_FRAME, "\tTSTFSZ\tWREG", f"\tBRA\t{SAVE}", "\tRETURN",
        # W (at least 1) registers from r0x00 upwards, as sdcc's own saves push them
        f"{SAVE}:", "\tLFSR\t0x00, r0x00", f"{SAVE}_next:", "\tMOVFF\tPOSTINC0, POSTDEC1",
        "\tDECFSZ\tWREG, F", f"\tBRA\t{SAVE}_next", "\tRETURN",
        # W (at least 1) bytes of arguments from FSR2 + 3 up into r0x00 up; W is
        # left as sdcc's own loads leave it, the last offset
        f"{LOAD_ARGS}:", "\tMOVWF\tPRODL", "\tLFSR\t0x00, r0x00", f"\tMOVLW\t0x{_FIRST_ARG - 1:02x}",
        f"{LOAD_ARGS}_next:", "\tADDLW\t0x01", "\tMOVFF\tPLUSW2, POSTINC0", "\tDECFSZ\tPRODL, F",
        f"\tBRA\t{LOAD_ARGS}_next", "\tRETURN",
        # entry k of a chain: k registers from r0x(k-1) down to r0x00
        *chain_plain, *(["\tRETURN"] if plain >= 1 else []),
        *chain_frame, *([f"{LEAVE_FRAME}0:", *_UNFRAME, "\tRETURN"] if frame >= 0 else []),
        "\tend", ""])
