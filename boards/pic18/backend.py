"""The PIC18 board's backend (boards/pic18/, docs/boards.md): the board
contract for the PIC18F4520 and PIC18F4620, driven by board.toml.

- ``configure``: the MCU (its memories, resources);
- ``check``: every resource claim against the MCU (the shared check of
  easylab.board.resources, with the port-and-bit pin names as aliases) and
  the part's own rule (ADCON1's analog pins), all problems in one error;
- ``produce``: the configuration, the device tables, the linker script;
- ``compile``: sdcc (sdcc.py: the 64-bit lowering, unreachable functions
  dropped) and gplink; the .hex, program memory and RAM against the part,
  failing when it does not fit;
- ``build_simulator``: the gpsim harness with the build's tables;
- ``flash_command``: Microchip's programmer command line (shown, not run).

It reads the IR only (and, for the source line of an interface, the model
file the IR names).
"""

from __future__ import annotations

import shlex
import subprocess
from pathlib import Path

from easylab.board import handlers, resources
from easylab.codegen.device_state import state_layout_source
from easylab.board.base import BoardBase
from easylab.board.cbuild import mode_flags, require_tool, runtime_sources, write_files
from easylab.board.contract import Compiled, CompileOptions, SizeReport, Simulator
from easylab.board.simtables import chip_files
from easylab.core.errors import BuildError
from easylab.core.paths import runtime_dir
from easylab.ir.program import Program

from . import devices, linkfail, linkmap, sdcc, sdcc_quirks, simulator
from .parts import read_mcus


class Pic18Board(BoardBase):
    has_simulator = True

    def __init__(self, description):
        super().__init__(description)
        self.all_mcus = read_mcus(description.table("mcu"))
        self.drivers: dict[str, dict] = description.table("drivers")
        self.clock_hz = int(description.raw.get("clock_hz", 40_000_000))
        self.persist_bytes = int(description.raw.get("persist_program_bytes", 0))  # what persist params cost

    @property
    def fcy(self) -> int:
        """Instruction cycles per second (four clocks each)."""
        return self.clock_hz // 4

    # ---------------------------------------------------------------- code

    def check(self, program: Program) -> resources.Resolved:
        # the part's own rule once the claims are right
        resolved = resources.check(program, self.name, self.part.part(), self.drivers,
                                   lambda prog, res: [] if res.problems else devices.analog_problems(prog, self.part))
        handlers.check_files(program, self.name)
        return resolved

    def produce(self, program: Program, checked: resources.Resolved, release: bool) -> dict[str, str]:
        """The configuration and device tables, and the handlers a model
        brings for the board (el_handlers.c: portable C, lowered and
        compiled as model.c is; they may use the MSSP's buses, el_bus.h)."""
        return {**devices.files(program, self, checked, release),
                **handlers.source(program, self.name, includes=("el_bus.h",), chip_select=self.chip_select),
                **(state_layout_source(program, self.name) if self.sim else {})}

    def device_call(self, device, handler: str) -> str:
        """A handler file's function is called by its name: el_pic18_devices.h
        declares it (devices.handler_declarations)."""
        call = handlers.call(device, handler, self.name)
        if call:
            return f"{handlers.function_name(device, handler)}();"
        return super().device_call(device, handler)

    def chip_select(self, pin: str) -> str:
        """A chip select for handler files (EL_CS): struct el_pin of el_board.h."""
        return devices.chip_select(self.part, pin)

    def _build(self, out_dir: Path, release: bool, extra: tuple[str, ...] = ()) -> sdcc.Build:
        folder = self.description.folder
        # EL_TICK_32: absolute ticks in 32 bits (runtime_c/el_types.h), no 64-bit sums per instant.
        # EL_WIDE_SOFTWARE: actors' wide arithmetic in el_wide.c's two words (runtime_c/el_wide.h):
        # sdcc gave wrong saturating products and sums through the 64-bit lowering.
        return sdcc.Build(sdcc.find_toolchain(), self.part.device,
                          [*mode_flags(release), "-DEL_TICK_32=1", "-DEL_WIDE_SOFTWARE=1", *extra],
                          [out_dir, runtime_dir(), *self.description.include_paths], out_dir / "obj",
                          folder / "el_pic18_w64.h")

    def _hardware(self) -> list[Path]:
        return [self.description.folder / s for s in self.description.raw.get("hardware_sources", [])]

    def _objects(self, build: sdcc.Build, portable: list[Path], out_dir: Path) -> tuple[list[Path], Path, int]:
        """Lower and compile the portable files, compile the hardware files;
        write the linker script (which knows where the big objects went).
        Returns the objects, the script and where the big objects begin."""
        require_tool("gplink", self.name, "gputils", "linker")
        hardware = self._hardware()
        lowered, big_start = build.portable(portable, sdcc.hardware_roots(build, hardware),
                                            self.part.stack_bottom - 1)
        lkr, stack = write_files(out_dir, {
            f"{self.part.name}.lkr": devices.linker_script(self.part, big_start=big_start),
            "el_pic18_stack.c": devices.stack_source(self.part)})
        return build.compile(lowered + hardware + [stack]), lkr, big_start

    def compile(self, program: Program, checked: object, out_dir: Path, generated: list[Path],
                options: CompileOptions) -> Compiled:
        """Compile and link for the MCU; write NAME.hex (and NAME.cod for
        gpsim, NAME.map); check that it fits."""
        if options.cc is not None:
            raise BuildError("board 'pic18' compiles with its sdcc only (--cc is for gcc-style boards)")
        mcu = self.part
        build = self._build(out_dir, options.release, options.extra_cflags)
        portable = [p for p in generated if p.suffix == ".c"] + runtime_sources(options.release) \
            + self.description.source_paths
        hexfile = out_dir / f"{program.name}.hex"
        try:
            objects, lkr, big_start = self._objects(build, portable, out_dir)
        except sdcc_quirks.BigObjectsDoNotFit as err:
            self._remove(hexfile)
            bigger = [m.name for m in self.all_mcus.values() if m.ram > mcu.ram]
            raise BuildError(f"the program does not fit the {mcu.name}'s {mcu.ram} bytes of RAM: {err}"
                             + ("; dataflow buffers shrink with --schedule min-buffer"
                                if options.schedule != "min-buffer" and any(df.buffers for df in program.dataflows)
                                else "") + (f"; or build for --mcu {bigger[0]}" if bigger else "")) from None
        try:
            lmap = linkmap.read_map(build.link_checked(objects, hexfile, lkr))
        except BuildError as err:
            unplaced = linkfail.unplaced_sections(str(err), objects)
            if not unplaced:
                raise
            self._remove(hexfile)
            measured = self._measure(build, objects, big_start, out_dir)
            raise BuildError(self._not_fit(program, measured, options, unplaced)) from None
        report = self.size_report(lmap)
        return Compiled(hexfile, portable + self._hardware(), report, image=hexfile, notes=list(build.notes))

    def _measure(self, build: sdcc.Build, objects: list[Path], big_start: int, out_dir: Path) -> linkmap.LinkMap:
        """A program too big for its part linked into the part's memory map
        grown to the PIC18's whole 2 MB of program memory and all the RAM
        below the registers, only to measure by how much (empty when that
        fails too)."""
        lkr = out_dir / "measure.lkr"
        write_files(out_dir, {lkr.name: devices.linker_script(self.part, big_start, measure=True)})
        try:
            return linkmap.read_map(build.link(objects, out_dir / "measure.hex", lkr))
        except BuildError:
            return linkmap.LinkMap()
        finally:
            self._remove(out_dir / "measure.hex")
            lkr.unlink()

    @staticmethod
    def _remove(hexfile: Path) -> None:
        for suffix in (".hex", ".cod", ".map", ".lst"):
            p = hexfile.with_suffix(suffix)
            if p.exists():
                p.unlink()

    # ---------------------------------------------------------------- sizes

    def size_report(self, lmap: linkmap.LinkMap) -> SizeReport:
        mcu = self.part
        line = (f"{mcu.name}: program memory {lmap.flash} of {mcu.flash} bytes ({100.0 * lmap.flash / mcu.flash:.1f} %), "
                f"RAM {lmap.ram} of {mcu.ram} bytes ({100.0 * lmap.ram / mcu.ram:.1f} %, static data and the "
                f"{lmap.stack}-byte stack)")
        return SizeReport(lmap.flash, lmap.ram, mcu.flash, mcu.ram, [line])

    def _not_fit(self, program: Program, measured: linkmap.LinkMap, options: CompileOptions,
                 unplaced: list[linkfail.Unplaced]) -> str:
        """The error of a program gplink could not place: its measured size
        and by how much each memory overflows (when the program links into
        the whole address space), gplink's own message with the section it
        names, and what would help."""
        mcu = self.part
        lines = []
        over = []
        if measured.sections:
            lines.append(f"{mcu.name}: program memory {measured.flash} of {mcu.flash} bytes, RAM {measured.ram} "
                         f"of {mcu.ram} bytes (static data and the {mcu.stack}-byte stack)")
            if measured.flash > mcu.flash:
                over.append(f"{mcu.flash} bytes of program memory ({measured.flash - mcu.flash} bytes too many)")
            if measured.ram > mcu.ram:
                over.append(f"{mcu.ram} bytes of RAM ({measured.ram - mcu.ram} bytes too many: static data plus "
                            f"the {mcu.stack}-byte stack)")
            flash_over, ram_over = measured.flash > mcu.flash, measured.ram > mcu.ram
        else:  # not even the whole address space holds it: what gplink named is all there is
            flash_over = any(u.memory == "program memory" for u in unplaced)
            ram_over = any(u.memory == "RAM" and not u.larger_than_a_bank for u in unplaced)
        too_wide = [u for u in unplaced if u.larger_than_a_bank]
        if over:
            msg = f"the program does not fit the {mcu.name}'s " + ", nor its ".join(over)
        elif too_wide:
            # a local array without an initializer is placed as a big object (sdcc_quirks._hoist_big_locals)
            msg = (f"the program does not fit the {mcu.name}'s RAM banks: gplink could not place a "
                   f"{too_wide[0].size}-byte RAM section, and a RAM section must fit within one "
                   f"{linkfail.BANK_BYTES}-byte bank (sdcc gives each function's local array a section of its "
                   f"own); a local array with an initializer stays there: a table that is only read can be "
                   f"'static const' (program memory), one that changes can be the actor's state")
        elif measured.sections:  # the totals fit, their parts do not
            msg = (f"gplink could not place the program's sections in the {mcu.name}'s memory, though "
                   f"in all they fit (each RAM section must fit within a {linkfail.BANK_BYTES}-byte bank)")
        else:
            memories = " and its ".join(m for m, o in (("program memory", flash_over), ("RAM", ram_over)) if o)
            msg = f"the program does not fit the {mcu.name}'s {memories or 'memory'}"
        if flash_over and not options.release and any(i.kind == "debug" for i in program.interfaces):
            msg += "; the debug server takes about 9 KB of program memory: a --release build has none"
        if ram_over and options.schedule != "min-buffer" and any(df.buffers for df in program.dataflows):
            msg += "; dataflow buffers shrink with --schedule min-buffer"
        if flash_over:
            msg += self._persist_hint(program, measured)
        bigger = [m for m in self.all_mcus.values()
                  if (flash_over and m.flash > mcu.flash) or (ram_over and m.ram > mcu.ram)]
        if bigger:
            msg += f"; or build for --mcu {bigger[0].name}"
        lines.append(("error: " if lines else "") + msg)
        lines += [u.describe() for u in unplaced]
        if measured.sections and (ram_over or not over):
            lines.append("largest in RAM: " + ", ".join(f"{name} {size} B ({src}.c)"
                                                        for size, name, src in measured.largest_ram()))
        return "\n".join(lines)

    def _persist_hint(self, program: Program, measured: linkmap.LinkMap) -> str:
        """What the program's persist params cost of program memory (board.toml
        ``persist_program_bytes``), for a program that overflows it; '' when
        it has none."""
        persist = [it.name for it in program.items if it.persist]
        if not persist or not self.persist_bytes:
            return ""
        n, mcu = self.persist_bytes, self.part
        fits = bool(measured.sections) and measured.flash - n <= mcu.flash
        return (f"; its {len(persist)} persist param{'s' if len(persist) != 1 else ''} ({', '.join(persist)}) "
                f"cost about {n / 1024:.1f} KB of program memory on the {mcu.name} ({n} bytes: the EEPROM records, "
                f"their checks and the service layer they are written through"
                f"{'; without persist the program would fit' if fits else ''}): drop persist from the params "
                f"that need not survive a reset")

    # ---------------------------------------------------------------- running, flashing

    def build_simulator(self, program: Program, checked: object, out_dir: Path, compiled: Compiled) -> Simulator:
        lmap = linkmap.read_map(compiled.executable.with_suffix(".map"))
        model = simulator.sim_model_source(program, self, compiled.executable, lmap, checked.uarts)
        exe = simulator.build_harness(self, out_dir, model, out_dir / f"{program.name}-sim", chip_files(program))
        return Simulator(exe, [])

    def simulator_command(self, out_dir: Path, program: Program) -> list[str]:
        """The harness with the EUSART on a pty in ``out_dir``."""
        return [str(out_dir / f"{program.name}-sim"), "--uart0", f"pty:{out_dir / 'uart0'}"]

    def flash_command(self, out_dir: Path, program: Program, port: str, programmer: str | None = None,
                      baud: int | None = None) -> list[str]:
        """Microchip's MPLAB IPE command line with the programmer on
        ``port`` (a PICkit is a USB device: the port is not passed)."""
        spec = self.description.table("flash")
        template = spec.get("command", "ipecmd.sh -TP{programmer} -P{part} -F{hex} -M -OL")
        return shlex.split(template.format(programmer=programmer or spec.get("programmer", "PK3"),
                                           part=self.part.programmer_part, hex=out_dir / f"{program.name}.hex"))

    def build_program(self, sources: list[Path], work_dir: Path, name: str,
                      runtime: tuple[str, ...] = ()) -> tuple[Path, linkmap.LinkMap]:
        """A program of our own (the port contract program, a benchmark)
        built against the port: ``sources`` (portable C defining el_run),
        the runtime files named in ``runtime``, the port; release flags.
        The configuration headers must be in ``work_dir`` (config_header,
        or a generated model's). Returns the .hex and its map."""
        build = self._build(work_dir, True)
        ports = [p for p in self.description.source_paths if p.name != "pic18_interfaces.c"]
        files = [*sources, *(p for p in runtime_sources(True) if p.name in runtime), *ports]
        hexfile = work_dir / f"{name}.hex"
        objects, lkr, _ = self._objects(build, files, work_dir)
        return hexfile, linkmap.read_map(build.link_checked(objects, hexfile, lkr))

    def run_port_program(self, source: Path, work_dir: Path) -> str:
        """The program on the MCU in gpsim; its report comes on the EUSART."""
        t = devices.tick_timer(1000, self.fcy)
        mcu = self.part
        write_files(work_dir, {
            "el_pic18_config.h": "\n".join([
                f"#define EL_PIC18_CONFIG_VERSION {devices.CONFIG_VERSION}",
                f"#define EL_PIC18_MCU_NAME \"{mcu.name}\"", f"#define EL_PIC18_FCY {self.fcy}UL",
                f"#define EL_PIC18_RAM_LAST 0x{mcu.ram_last:03X}", f"#define EL_PIC18_RAM_TOP 0x{mcu.ram_last + 1:03X}",
                f"#define EL_PIC18_NV_SIZE {mcu.eeprom}u", f"#define EL_PIC18_TICK_T2CON 0x{t.t2con:02X}u",
                f"#define EL_PIC18_TICK_PR2 {t.pr2}u", f"#define EL_PIC18_TICK_ISRS {t.isrs}u",
                "#define EL_PIC18_ADC_CHANNELS 0u", "#define EL_PIC18_ENCODERS 0u", ""]),
            "el_pic18_devices.h": "/* no devices */\n"})
        hexfile, lmap = self.build_program([source], work_dir, source.stem)
        harness = simulator.build_harness(self, work_dir, simulator.port_program_tables(self, hexfile, lmap),
                                          work_dir / f"{source.stem}-sim")
        report = work_dir / "uart0.txt"
        proc = subprocess.run([str(harness), "--fast", "--uart0", f"file:{report}", "--cycles", "20000000"],
                              capture_output=True, text=True, timeout=300, stdin=subprocess.DEVNULL)
        if proc.returncode != 0:
            raise BuildError(f"the simulation of {source.name} failed: {proc.stderr.strip()}")
        return report.read_text()

    def symbols(self, compiled: Compiled) -> set[str]:
        lmap = linkmap.read_map(compiled.executable.with_suffix(".map"))
        return {name[1:] for name in lmap.symbols if name.startswith("_")}
