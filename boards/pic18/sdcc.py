"""The PIC18 board's compiler: sdcc's pic16 port, built once into a cache
by boards/pic18/toolchain/build.sh (`make setup`), and gputils' linker.

A build goes in two kinds of C files:
- portable ones (the runtime, the generated files, the port's portable
  part, the drivers through model.c): preprocessed by sdcc, parsed, their
  64-bit integers lowered (lower64.py) and unreachable functions dropped
  across the whole program (prune.py), then compiled;
- hardware ones (registers, the interrupt handler, configuration bits,
  inline assembly: compiler keywords behind el_pic18.h's macros), compiled
  as they are. They never see a 64-bit type.
gplink then links them with sdcc's start-up code and libraries, and the
map file gives the sizes and the symbols' addresses. What sdcc gets wrong
is kept out (docs/boards.md, "What sdcc gets wrong"): passes on the C
(boolconv.py, shifts.py), its faulty bank optimisation off, the linked
program's bank selection checked (bankcheck.py, a file with a fault
compiled again), and a file sdcc crashes on compiled again with fewer
optimisations.
"""

from __future__ import annotations

import os
import re
import subprocess
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

from pycparser import c_ast, c_generator, c_parser

from easylab.core.errors import BuildError

from . import (bankcheck, boolconv, buildcache, ctypes64, datapointers, inline, linkmap, lower64, lower64_stmt,
               messages, prune, saves, sdcc_quirks, selfops, shifts, strength)
from .ctypes64 import LowerError, Target
from .lower64_stmt import lower_unit

VERSION_FOLDER = "sdcc-pic16-4.2.0-2"  # boards/pic18/toolchain/build.sh's folder in the cache
OVERRIDE = "EASYLAB_PIC18_SDCC"  # another folder holding such a build
STAMP = ".easylab-complete"
SDCC_TIMEOUT = 300  # seconds: sdcc can hang on huge arrays
TARGET = Target(int_bits=16, long_bits=32, char_signed=False)
# sdcc's own library build uses these; about 8 % smaller code, but not
# its --optimize-cmp: that pCode rewrite turns a comparison sdcc has
# decided false (`a < b` once an inlined b is 0, on an unsigned a) into a
# test of a against zero, `a != 0`: `p >= 0` was false for every p > 0.
# The large stack model: the software stack is larger than a bank
# (el_pic18_stack.c).
# --obanksel=1: sdcc drops a BANKSEL after an instruction naming the same
# operand; its levels above 1 also drop one for another offset of the same
# symbol, which sits in another bank when the object is larger than a bank
# (sdcc_quirks.place_big_objects): a read under the bank of the last store.
OPT_FLAGS = ("--pstack-model=large", "--fomit-frame-pointer", "--obanksel=1", "--denable-peeps", "--optimize-df")
# A file whose assembly fails the bank check (bankcheck.py) again: a BANKSEL
# before every banked access.
SAFE_BANKS = ("--pstack-model=large", "--fomit-frame-pointer", "--obanksel=0", "--denable-peeps", "--optimize-df")
# When sdcc crashes on a file (an internal error, a signal), the file again
# with fewer optimisations, in turn: without the pCode optimisations, then
# without the iCode ones as well (SDCCopt.c's asserts).
FALLBACKS = (("--pstack-model=large", "--fomit-frame-pointer", "--obanksel=0", "--no-peep"),
             ("--pstack-model=large", "--fomit-frame-pointer", "--obanksel=0", "--no-peep", "--nogcse",
              "--noinvariant", "--noinduction", "--noloopreverse", "--nolabelopt", "--nolospre"))
# Warnings are errors, but those that say nothing about the C: sdcc 4.2's
# pic16 port warns "Initializer different levels of indirections" (18) for
# every address of a RAM object in a static initializer of a generic
# pointer (`(void *)&x` in el_items) and emits the right pointer (address
# and the data-space tag 0x80) all the same; "conditional flow changed by
# optimizer" (110) and "unreachable code" (126) say that a condition's
# value was known at compile time, as it is where portable code tests a
# board's configuration macros (PC_EXACT_TICKS || ...). gcc's -Wall -Wextra
# -Werror on the same C catches real mismatches.
# "integer overflow in expression" (165) comes from sdcc's constant folding
# of an unsigned product it has narrowed itself (`(uint16_t)(a * 1000u)`
# with a known a: its 16-bit product wraps, as C's unsigned arithmetic
# does), not from the C.
WARNING_FLAGS = ["--Werror", "--disable-warning", "18", "--disable-warning", "110", "--disable-warning", "126",
                 "--disable-warning", "165"]
_WORD = re.compile(r"\b[A-Za-z_]\w*\b")
# The assembly passes' code: a cached object is of this code.
_ASM_PASSES_VERSION = buildcache.code_version(boolconv, sdcc_quirks, saves)


@dataclass
class Toolchain:
    root: Path

    @property
    def sdcc(self) -> Path:
        return self.root / "bin" / "sdcc"

    @property
    def lib(self) -> Path:
        return self.root / "share" / "sdcc" / "lib" / "pic16"


def default_root() -> Path:
    cache = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return cache / "easylab" / VERSION_FOLDER


def find_toolchain() -> Toolchain:
    """The built toolchain, or a BuildError saying how to get it."""
    root = Path(os.environ[OVERRIDE]) if os.environ.get(OVERRIDE) else default_root()
    if not (root / STAMP).is_file() or not (root / "bin" / "sdcc").is_file():
        script = Path(__file__).resolve().parent / "toolchain" / "build.sh"
        raise BuildError(
            f"the pic18 board's compiler (sdcc with its pic16 port) is not built in {root}: Debian's sdcc lacks "
            f"the PIC ports. `make setup` builds it once from Debian's sdcc source (a few minutes, as root), or "
            f"run {script} yourself; {OVERRIDE} names another folder holding such a build")
    return Toolchain(root)


def _run(cmd: list, what: str, cwd: Path | None = None) -> subprocess.CompletedProcess:
    try:
        proc = subprocess.run([str(c) for c in cmd], capture_output=True, text=True, timeout=SDCC_TIMEOUT,
                              cwd=cwd, stdin=subprocess.DEVNULL)
    except subprocess.TimeoutExpired:
        raise BuildError(f"{what}: {Path(str(cmd[0])).name} did not finish in {SDCC_TIMEOUT} s") from None
    except FileNotFoundError:
        raise BuildError(f"{what}: {cmd[0]} is not installed (Debian package: gputils)") from None
    if proc.returncode != 0:
        text = "\n".join(line for line in (proc.stdout + proc.stderr).splitlines()
                         if "Message[" not in line and line.strip())
        raise BuildError(f"{what} failed:\n{text}".rstrip())
    return proc


@dataclass
class Build:
    """One program's compile: flags shared by every file."""

    tc: Toolchain
    part: str  # "18f4520"
    defines: list[str]  # -D...
    include_dirs: list[Path]
    obj_dir: Path
    w64_header: Path  # el_pic18_w64.h
    notes: list[str] = field(default_factory=list)
    in_ram: set[str] = field(default_factory=set)  # the program's RAM objects (sdcc_quirks.ram_pointer_tags)
    file_flags: dict[str, tuple[str, ...]] = field(default_factory=dict)  # a file's own flags (by stem)
    sources: dict[Path, Path] = field(default_factory=dict)  # object -> the file it was compiled from

    def __post_init__(self) -> None:
        # sdcc and gpasm run inside obj_dir: every path they see is absolute
        self.obj_dir = self.obj_dir.resolve()
        self.include_dirs = [d.resolve() for d in self.include_dirs]

    def flags(self, opts: tuple[str, ...] = OPT_FLAGS) -> list[str]:
        """sdcc's options with the optimisation options ``opts``."""
        return ["-mpic16", f"-p{self.part}", "--std-c99", "--no-warn-non-free", *WARNING_FLAGS, *opts,
                *self.defines, *(f"-I{d}" for d in self.include_dirs)]

    # ---- portable files

    def preprocess(self, source: Path) -> str:
        """The file as sdcc's preprocessor gives it, with the lowering's
        view of 64-bit integers (el_pic18_w64.h) and the board's table reads
        (el_pic18_rom.h) in front."""
        self.obj_dir.mkdir(parents=True, exist_ok=True)
        wrapper = self.obj_dir / f"{source.stem}.lower.c"
        rom = self.w64_header.parent / "el_pic18_rom.h"
        wrapper.write_text(f'#include "{self.w64_header}"\n#include "{rom}"\n#include "{source.resolve()}"\n',
                           encoding="utf-8")
        proc = _run([self.tc.sdcc, *self.flags(), "-DEL_W64_LOWERING=1", "-E", wrapper],
                    f"preprocessing {source.name}")
        return proc.stdout

    def portable(self, sources: list[Path], roots: set[str], ram_end: int) -> tuple[list[Path], int]:
        """Preprocess, lower and prune the portable files, place the objects
        larger than a bank below ``ram_end``; write the C that sdcc compiles
        (obj_dir/NAME.sdcc.c). Returns the files and where the placed
        objects begin (``ram_end`` + 1 when there are none)."""
        with ThreadPoolExecutor(max_workers=2) as pool:
            texts = list(pool.map(self.preprocess, sources))
        units = {src.stem + ("_gen" if src.resolve().parent == self.obj_dir.parent else ""): lowered(src, text)
                 for src, text in zip(sources, texts)}
        prune.prune(units, roots)
        for ast in units.values():
            inline.inline_single_calls(ast)
            strength.reduce_products(ast, TARGET)
            shifts.split_shifts(ast)
            selfops.rewrite_self_operations(ast)
            boolconv.fix_bool_conversions(ast, TARGET)
            datapointers.data_pointers(ast)
        big_start = sdcc_quirks.place_big_objects(units, TARGET, ram_end)
        self.in_ram = sdcc_quirks.fix_initializers(units, TARGET)
        sdcc_quirks.drop_zero_initializers(units)
        out = []
        gen = _LineGenerator()
        for name, ast in units.items():
            path = self.obj_dir / f"{name}.sdcc.c"
            text = f"/* {name}: lowered for sdcc (boards/pic18/lower64.py). Do not edit. */\n" + gen.visit(ast)
            if not path.exists() or path.read_text(encoding="utf-8") != text:
                path.write_text(text, encoding="utf-8")
            out.append(path)
        return out, big_start

    # ---- compiling, linking

    def compile(self, sources: list[Path]) -> list[Path]:
        """sdcc -c for each file, in parallel (``compile_one``)."""
        self.obj_dir.mkdir(parents=True, exist_ok=True)
        with ThreadPoolExecutor(max_workers=2) as pool:
            return list(pool.map(self.compile_one, sources))

    def compile_one(self, src: Path, fallbacks: tuple[tuple[str, ...], ...] = FALLBACKS) -> Path:
        """One file to an object (and its assembly, kept for the bank check).
        An object compiled before from the same text with the same flags
        comes from the build cache (a hardware file's text is its
        preprocessed text). When sdcc crashes on the file, it is compiled
        again with each of ``fallbacks``' optimisations off in turn (a
        crash is sdcc's, never the model's); what it then says is reported."""
        stem = src.name.removesuffix(".sdcc.c").removesuffix(".c")
        obj, asm = self.obj_dir / f"{stem}.o", self.obj_dir / f"{stem}.asm"
        self.obj_dir.mkdir(parents=True, exist_ok=True)
        self.sources[obj] = src
        text = src.read_bytes() if src.resolve().parent == self.obj_dir else \
            _run([self.tc.sdcc, *self.flags(), "-E", src], f"preprocessing {src.name}").stdout.encode()
        opts = self.file_flags.get(stem, OPT_FLAGS)
        digest = buildcache.key(str(self.tc.root), *self.flags(opts), text, " ".join(sorted(self.in_ram)),
                                _ASM_PASSES_VERSION)
        if buildcache.fetch_file("sdcc", digest, obj) and buildcache.fetch_file("sdcc-asm", digest, asm):
            return obj
        for k, attempt in enumerate((opts,) + fallbacks):
            try:
                _run([self.tc.sdcc, *self.flags(attempt), "-S", src.resolve(), "-o", asm],
                     f"compiling {src.name} with sdcc", cwd=self.obj_dir)
                break
            except BuildError as err:
                if not crashed(str(err)):
                    raise BuildError(messages.in_model_terms(str(err))) from None
                if k == len(fallbacks):
                    raise BuildError(f"sdcc failed on {src.name} (it crashed, with each set of optimisations "
                                     f"the board tries, the last {' '.join(attempt)}); the C it was given: "
                                     f"{src}") from None
                self.notes.append(f"{src.name}: sdcc crashed; compiled with {' '.join(fallbacks[k])}")
        text, _ = boolconv.fix_bool_casts_in_asm(asm.read_text(encoding="latin-1"))
        asm.write_text(saves.share_saves(sdcc_quirks.ram_pointer_tags(text, self.in_ram)), encoding="latin-1")
        _run(["gpasm", "-D__STACK_MODEL_LARGE", "-o", obj, "-c", asm], f"assembling {asm.name}", cwd=self.obj_dir)
        buildcache.store_file("sdcc", digest, obj)
        buildcache.store_file("sdcc-asm", digest, asm)
        return obj

    def link_checked(self, objects: list[Path], hexfile: Path, lkr: Path) -> Path:
        """Link, then check every banked access against BSR (bankcheck.py);
        a file with faults is compiled again with sdcc's bank optimisation
        off (SAFE_BANKS) and the program linked again. Faults that remain
        fail the build. Returns the map file."""
        lmap_path = self.link(objects, hexfile, lkr)
        faulty = self._bank_faults(objects, lmap_path)
        if not faulty:
            return lmap_path
        for obj in faulty:
            stem = obj.stem
            self.file_flags[stem] = SAFE_BANKS
            self.notes.append(f"{self.sources[obj].name}: a BANKSEL sdcc left out; compiled with --obanksel=0")
            self.compile_one(self.sources[obj])
        lmap_path = self.link(objects, hexfile, lkr)
        faulty = self._bank_faults(objects, lmap_path)
        if faulty:
            raise BuildError("sdcc's assembly reads or writes RAM under the wrong bank:\n" + "\n".join(
                str(f) for faults in faulty.values() for f in faults[:5]))
        return lmap_path

    def _bank_faults(self, objects: list[Path], map_path: Path) -> dict[Path, list]:
        lmap = linkmap.read_map(map_path)
        found = {}
        for obj in objects:
            asm = obj.with_suffix(".asm")
            if asm.is_file():
                faults = bankcheck.check(asm.read_text(encoding="latin-1"), asm.resolve(), lmap)
                if faults:
                    found[obj] = faults
        return found

    def link(self, objects: list[Path], hexfile: Path, lkr: Path) -> Path:
        """gplink with sdcc's libraries (the start-up code is the board's
        own, pic18_startup.c); writes NAME.hex, NAME.cod, NAME.map."""
        lib = self.tc.lib
        _run(["gplink", "-m", "-w", "-s", lkr, "-I", lib, "-o", hexfile, *objects, *self._saves_object(objects),
              f"libdev{self.part}.lib", "libsdcc.lib", "libc18f.lib", "libm18f.lib"], "linking with gplink")
        return hexfile.with_suffix(".map")

    def _saves_object(self, objects: list[Path]) -> list[Path]:
        """The shared register saves and restores the objects call
        (saves.py), assembled; none when they call none."""
        plain, frame = saves.longest_restores([o.with_suffix(".asm").read_text(encoding="latin-1")
                                               for o in objects if o.with_suffix(".asm").is_file()])
        if plain < 0 and frame < 0:
            return []
        asm = self.obj_dir / f"{saves.MODULE}.asm"
        asm.write_text(saves.routines(self.part, plain, frame), encoding="latin-1")
        obj = asm.with_suffix(".o")
        _run(["gpasm", "-o", obj, "-c", asm], f"assembling {asm.name}", cwd=self.obj_dir)
        return [obj]


class _LineGenerator(c_generator.CGenerator):
    """C from a syntax tree with a `#line` before each statement: sdcc's
    messages name the file and line the statement came from (model.c, a
    runtime file), not the lowered text it compiles."""

    def _generate_stmt(self, n: c_ast.Node, add_indent: bool = False) -> str:
        text = super()._generate_stmt(n, add_indent)
        coord = getattr(n, "coord", None)
        if coord is None or not coord.file or not coord.line or isinstance(n, c_ast.Compound):
            return text
        name = str(coord.file).replace("\\", "\\\\").replace('"', '\\"')
        return f'#line {coord.line} "{name}"\n' + text


_LOWERING = buildcache.code_version(ctypes64, lower64, lower64_stmt)


def lowered(src: Path, text: str) -> c_ast.FileAST:
    """A preprocessed file parsed and lowered (from the build cache when this
    text was lowered before by this code)."""
    digest = buildcache.key(_LOWERING, text)
    ast = buildcache.fetch_object("lowered", digest)
    if ast is not None:
        return ast
    try:
        ast = c_parser.CParser().parse(text, str(src))
        lower_unit(ast, TARGET)
    except LowerError as err:
        raise BuildError(f"{src.name}: {err}") from None
    except Exception as err:  # pycparser's ParseError and the like
        raise BuildError(f"parsing {src.name} for the 64-bit lowering failed: {err}") from None
    buildcache.store_object("lowered", digest, ast)
    return ast


def crashed(message: str) -> bool:
    """sdcc failed of itself, not because of the C: an internal error, an
    assertion, a signal."""
    return any(k in message for k in ("Internal Error", "internal error", "Caught signal", "Assertion",
                                      "Segmentation fault", "Aborted"))


def hardware_roots(build: Build, sources: list[Path]) -> set[str]:
    """Every name the hardware files mention: functions of the portable
    files they call stay in the program."""
    names: set[str] = {"main"}
    for src in sources:
        text = _run([build.tc.sdcc, *build.flags(), "-E", src], f"preprocessing {src.name}").stdout
        names |= set(_WORD.findall(text))
    return names
