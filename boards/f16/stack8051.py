"""The 16-bit proxy's stack, bounded at build time (docs/boards.md, "The
F16 board").

The proxy's image is built with ``--stack-auto``: every function keeps its
locals and arguments on the 8051's hardware stack, which lives in the
internal RAM left over by the registers and bits, some 220 bytes. A model
whose deepest call chain needs more overwrites its registers and returns
to address 0, and s51 says nothing about it (the program starts again). So
a build adds up, from the assembly sdcc wrote, how far each function moves
the stack pointer (return addresses, pushes, ``sp`` arithmetic), follows
every call (through a function pointer: to every function whose address
the program takes), and bounds what the main program plus its
deepest interrupt needs, against what the linker left (sdcc's .mem).
The bound covers every path, the debugger's halt inside a dataflow serving
the service interface included, so most programs run well within the
stack although their bound is above it; the runner names the bound when a
program does overflow (it starts again from its reset vector).

sdcc's library functions (long division, floats, generic pointers) are
measured the same way from the library's own sources, compiled once with
the proxy's memory model and kept in ``${XDG_CACHE_HOME:-~/.cache}/
easylab/f16-proxy/``.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import tempfile
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path


# The library's entry that calls through the function pointer in dptr.
INDIRECT = "__sdcc_call_dptr"
# The interrupt vector table sdcc writes with main's module: a jump to the
# start-up code, then one to each interrupt routine.
_VECTORS = "__interrupt_vect"
# the start-up code: the reset vector's and, in the same module, the jump
# from the static initialisation to main
_STARTUP = {"__sdcc_gsinit_startup", "__sdcc_program_startup"}
_RETURN_ADDRESS = 2
_ENDS_FLOW = {"ret", "reti", "ljmp", "sjmp", "ajmp", "jmp"}
_LABEL = re.compile(r"^\s*([A-Za-z_]\w*)::?\s*(;.*)?$")
_INSTRUCTION = re.compile(r"^\s+([a-z]+)\b\s*([^;]*)")
_DATA = re.compile(r"^\s+\.(byte|db|dw|word)\b(.*)$")
_IMMEDIATE_NAME = re.compile(r"#\(?\s*([A-Za-z_]\w*)")


@dataclass
class Routine:
    """One function's own stack use and its calls."""

    name: str
    peak: int = 0  # bytes beyond its return address, at most
    calls: list[tuple[str, int]] = field(default_factory=list)  # (callee, bytes in use at the call)
    unbounded: bool = False  # sets sp from a value this reading does not follow
    code: bool = False  # has instructions (not a data label)


@dataclass
class Program:
    routines: dict[str, Routine] = field(default_factory=dict)
    address_taken: set[str] = field(default_factory=set)


def _signed8(value: int) -> int:
    value &= 0xFF
    return value - 0x100 if value & 0x80 else value


def _entries(text: str) -> set[str]:
    """The labels that start a routine: sdcc's functions, the names a file
    exports (``.globl``, ``name::``) and the targets of its calls; every
    other label belongs to the routine around it."""
    names = set(re.findall(r"^;\s+function (\w+)", text, re.M))
    entries = {f"_{n}" for n in names}
    entries.update(re.findall(r"^\s+\.globl\s+([A-Za-z_]\w*)", text, re.M))
    entries.update(re.findall(r"^\s*([A-Za-z_]\w*)::", text, re.M))
    entries.update(re.findall(r"^\s+[la]call\s+([A-Za-z_]\w*)", text, re.M))
    return entries | {_VECTORS}


def read_assembly(text: str, program: Program) -> None:
    """Add one sdcc assembly file's routines to ``program``."""
    entries = _entries(text)
    current: Routine | None = None
    depth = 0
    acc: int | None = None  # a's value as sp + k, when known
    frame = 0  # _bp's value as a depth
    falls_through = False
    prologue = False  # a is sp plus the frame being set up
    trampoline: int | None = None  # depth before sdcc's `lcall N$` ... `ret` call through a pointer
    for line in text.splitlines():
        data = _DATA.match(line)
        if data:
            program.address_taken.update(re.findall(r"[A-Za-z_]\w*", data.group(2)))
            continue
        label = _LABEL.match(line)
        if label and label.group(1) in entries:
            name = label.group(1)
            routine = Routine(name)
            if current is not None and falls_through and current.name != _VECTORS:
                current.calls.append((name, depth))
            program.routines.setdefault(name, routine)
            current, depth, acc, frame, falls_through, trampoline = routine, 0, None, 0, False, None
            continue
        ins = _INSTRUCTION.match(line)
        if current is None or not ins:
            continue
        op = ins.group(1)
        args = [a.strip() for a in ins.group(2).split(",")] if ins.group(2).strip() else []
        for arg in args:
            program.address_taken.update(_IMMEDIATE_NAME.findall(arg))
        falls_through = op not in _ENDS_FLOW
        current.code = True
        if op in ("lcall", "acall") and args and not re.fullmatch(r"[A-Za-z_]\w*", args[0]):
            # sdcc's call through a pointer: the local routine pushes the
            # target's address and returns into it
            current.calls.append((INDIRECT, depth + _RETURN_ADDRESS))
            trampoline, depth = depth, depth + _RETURN_ADDRESS
        elif op == "ret" and trampoline is not None:
            depth, trampoline = trampoline, None
        elif op == "push":
            depth += 1
        elif op == "pop":
            depth -= 1
        elif op in ("inc", "dec") and args == ["sp"]:
            depth += 1 if op == "inc" else -1
        elif op == "mov" and args == ["a", "sp"]:
            acc, prologue = depth, False
        elif op == "add" and len(args) == 2 and args[0] == "a" and acc is not None and args[1].startswith("#"):
            try:
                value = int(args[1][1:], 0)
                # 8-bit: a prologue allocates (up to 255 bytes of locals),
                # anything else frees arguments (0xfb is -5)
                acc += value if prologue else _signed8(value)
            except ValueError:
                acc = None
        elif op == "mov" and args == ["_bp", "a"]:
            frame = acc if acc is not None else frame
            prologue = acc is not None
            continue
        elif op == "mov" and args == ["_bp", "sp"]:
            frame = depth
        elif op == "mov" and args == ["sp", "a"]:
            if acc is None:
                current.unbounded = True
            else:
                depth = acc
        elif op == "mov" and args == ["sp", "_bp"]:
            depth = frame
        elif op == "mov" and args and args[0] == "sp":
            current.unbounded = True
        elif op in ("lcall", "acall") and args:
            current.calls.append((args[0], depth + _RETURN_ADDRESS))
        elif op in ("ljmp", "ajmp", "sjmp") and args and re.fullmatch(r"[A-Za-z_]\w*", args[0]):
            current.calls.append((args[0], depth))  # a tail call
        elif args and args[0] in ("a", "acc") and op not in ("push", "cjne", "jz", "jnz"):
            acc = None
        current.peak = max(current.peak, depth)


class StackBound:
    """The deepest stack each routine needs, over its calls; None where it
    cannot be bounded (an sp this reading does not follow, a call through a
    pointer with no known target, an unknown routine, recursion)."""

    def __init__(self, program: Program, library: dict[str, int | None]):
        self.program = program
        self.library = library
        self.memo: dict[str, int | None] = {}
        self.targets = sorted(n for n in program.address_taken if n in program.routines and program.routines[n].code)

    def need(self, name: str, active: frozenset[str] = frozenset()) -> int | None:
        """Bytes ``name`` and its callees push beyond its return address."""
        if name in self.memo:
            return self.memo[name]
        if name == INDIRECT:
            return self._indirect(active)
        routine = self.program.routines.get(name)
        if routine is None:
            return self.library.get(name)
        if routine.unbounded or name in active:
            return None
        worst: int | None = routine.peak
        for callee, at in routine.calls:
            below = self.need(callee, active | {name})
            if below is None:
                worst = None
                break
            worst = max(worst, at + below)
        self.memo[name] = worst
        return worst

    def _indirect(self, active: frozenset[str]) -> int | None:
        if not self.targets:
            return None
        needs = [self.need(t, active) for t in self.targets]
        return None if None in needs else max(needs)

    def interrupts(self) -> list[str]:
        """The routines the interrupt vectors jump to."""
        vectors = self.program.routines.get(_VECTORS)
        return sorted({c for c, _ in vectors.calls if c not in _STARTUP}) if vectors else []


def _library_sources() -> Path | None:
    sdcc = shutil.which("sdcc")
    if sdcc is None:
        return None
    folder = Path(sdcc).resolve().parent.parent / "share" / "sdcc" / "lib" / "src"
    return folder if folder.is_dir() else None


def _sdcc_version(sdcc: list[str]) -> str:
    proc = subprocess.run([sdcc[0], "--version"], capture_output=True, text=True)
    return re.sub(r"[^\w.-]+", "_", (proc.stdout.splitlines() or ["unknown"])[0])[:80]


def library_needs(sdcc: list[str], memory_flags: list[str]) -> dict[str, int | None]:
    """Each sdcc library routine's stack need under ``memory_flags``, from
    the library's sources (cached per sdcc version and flags)."""
    src = _library_sources()
    if src is None:
        return {}
    cache = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "easylab" / "f16-proxy"
    key = _sdcc_version(sdcc) + "-" + "_".join(f.strip("-") for f in memory_flags)
    path = cache / f"library-stack-{key}.json"
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        pass
    program = Program()
    with tempfile.TemporaryDirectory() as tmp:
        def compile_one(c: Path) -> None:
            subprocess.run([sdcc[0], *memory_flags, "-S", f"-I{src.parent.parent / 'include'}", "-o",
                            str(Path(tmp) / f"{c.stem}.asm"), str(c)], capture_output=True, text=True)

        with ThreadPoolExecutor(max_workers=4) as pool:
            list(pool.map(compile_one, sorted(src.glob("*.c"))))
        for asm in sorted([*Path(tmp).glob("*.asm"), *(src / "mcs51").glob("*.asm")]):
            read_assembly(asm.read_text(errors="replace"), program)
    bound = StackBound(program, {})
    needs = {name: bound.need(name) for name in program.routines}
    try:
        cache.mkdir(parents=True, exist_ok=True)
        fd, tmp_name = tempfile.mkstemp(dir=cache)
        with os.fdopen(fd, "w") as f:
            json.dump(needs, f)
        os.replace(tmp_name, path)
    except OSError:
        pass  # no cache: measured again next time
    return needs


def stack_available(mem_text: str) -> int | None:
    """The bytes of internal RAM the linker left for the stack (.mem)."""
    m = re.search(r"Stack starts at: 0x[0-9A-Fa-f]+ \(sp set to 0x[0-9A-Fa-f]+\) with (\d+) bytes available",
                  mem_text)
    return int(m.group(1)) if m else None


@dataclass
class StackReport:
    need: int | None  # bytes, None when some chain cannot be bounded
    available: int | None
    chain: list[str]  # the deepest call chain of the main program


def measure(asm_files: list[Path], mem_text: str, library: dict[str, int | None]) -> StackReport:
    """The image's stack need: main (called by the start-up code) plus the
    deepest interrupt routine, each with its return address."""
    program = Program()
    for asm in asm_files:
        read_assembly(asm.read_text(errors="replace"), program)
    bound = StackBound(program, library)
    main = bound.need("_main")
    isr_needs = [bound.need(n) for n in bound.interrupts()]
    need = None
    if main is not None and None not in isr_needs:
        need = _RETURN_ADDRESS + main + max((_RETURN_ADDRESS + n for n in isr_needs), default=0)
    return StackReport(need, stack_available(mem_text), _deepest_chain(bound, "_main"))


def _deepest_chain(bound: StackBound, start: str) -> list[str]:
    chain = [start]
    name = start
    while len(chain) < 64:
        routine = bound.program.routines.get(name)
        if routine is None:
            break
        best: tuple[int, str] | None = None
        for callee, at in routine.calls:
            below = bound.need(callee)
            if below is not None and (best is None or at + below > best[0]):
                best = (at + below, callee)
        if best is None or best[0] <= routine.peak:
            break
        name = best[1]
        chain.append(name)
    return [n[1:] if n.startswith("_") else n for n in chain]


def write_report(asm_files: list[Path], ihx: Path, library: dict[str, int | None]) -> StackReport:
    """Measure a linked image's stack need and keep it beside the image
    (NAME.stack.json), for the runner's word when the program overflows."""
    mem = ihx.with_suffix(".mem")
    report = measure(asm_files, mem.read_text() if mem.exists() else "", library)
    ihx.with_suffix(".stack.json").write_text(json.dumps(
        {"need": report.need, "available": report.available, "chain": report.chain}))
    return report


def describe(ihx: Path) -> str:
    """One sentence on an image's stack bound ('' when it has none): the
    deepest call chain is a bound over every path, the debugger's and the
    service interface's included, so a program may run well within it."""
    try:
        data = json.loads(ihx.with_suffix(".stack.json").read_text())
    except (OSError, ValueError):
        return ""
    if not data.get("need") or not data.get("available"):
        return ""
    return (f"the build bounds its deepest call chain at {data['need']} bytes of stack, {data['available']} are "
            f"free: {' -> '.join(data['chain'])}")
