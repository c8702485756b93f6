"""The AVR board's backend (boards/avr/, docs/boards.md): the board contract
for the ATmega328P and ATmega2560, driven by board.toml.

- ``configure``: the MCU (its memories, resources, avr-gcc flags);
- ``check``: every resource claim against the MCU and every device against
  the board's drivers (the shared check of easylab.board.resources), all
  problems in one error, each at its source line;
- ``produce``: the device tables and configuration (devices.py);
- ``compile``: avr-gcc, the .hex (without simavr's .mmcu section) and the
  flash and RAM use against the part, failing when it does not fit;
- ``build_simulator``: the simavr harness with the build's tables
  (simulator.py);
- ``flash_command``: avrdude through the board's bootloader.

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
from easylab.board.cbuild import (compile_objects, dispatcher_width_flags, elf_sections, include_flags, mode_flags,
                                  require_tool, run,
                                  runtime_sources, write_files)
from easylab.board.contract import Compiled, CompileOptions, SizeReport, Simulator
from easylab.board.simtables import chip_files, kept_symbols
from easylab.core.errors import BuildError
from easylab.ir.program import Program

from . import devices, simulator
from .parts import read_mcus

# Bytes of RAM left for the stack at the least: interrupt handlers, the
# dispatcher and the deepest actor call chain.
STACK_RESERVE = 256
_PACKAGES = "gcc-avr binutils-avr avr-libc"


class AvrBoard(BoardBase):
    has_simulator = True

    def __init__(self, description):
        super().__init__(description)
        self.all_mcus = read_mcus(description.table("mcu"))
        self.drivers: dict[str, dict] = description.table("drivers")
        self.clock_hz = int(description.raw.get("clock_hz", 16_000_000))
        self.watchdog_ms = int(description.raw.get("watchdog_ms", 2000))

    @property
    def cflags(self) -> list[str]:
        return [f"-mmcu={self.part.name}", f"-DF_CPU={self.clock_hz}UL", *self.description.toolchain.cflags]

    def _tool(self, role: str, default: str) -> str:
        return self.description.toolchain.tool(role, default)

    # ---------------------------------------------------------------- code

    def check(self, program: Program) -> resources.Resolved:
        resolved = resources.check(program, self.name, self.part.part(), self.drivers)
        handlers.check_files(program, self.name)
        return resolved

    def produce(self, program: Program, checked: resources.Resolved, release: bool) -> dict[str, str]:
        """The device tables and configuration, and the handlers a model
        brings for the board (they may use the I2C bus: el_bus.h)."""
        return {**devices.files(program, self, checked, release),
                **handlers.source(program, self.name, includes=("el_bus.h",), chip_select=self.chip_select),
                **(state_layout_source(program, self.name) if self.sim else {})}

    def chip_select(self, pin: str) -> str:
        """A chip select for handler files (EL_CS): struct el_pin of el_board.h."""
        return devices.chip_select(pin)

    def compile(self, program: Program, checked: object, out_dir: Path, generated: list[Path],
                options: CompileOptions) -> Compiled:
        """Compile and link for the MCU; write NAME.elf and NAME.hex; check
        that it fits."""
        compiler = options.cc or self.description.toolchain.cc
        require_tool(compiler, self.name, _PACKAGES)
        sources = [p for p in generated if p.suffix == ".c"] + runtime_sources(options.release) \
            + self.description.source_paths
        # The dispatcher as narrow as the program allows (docs/ir.md, "Dispatcher widths").
        flags = [*self.cflags, *mode_flags(options.release), *dispatcher_width_flags(program), *options.extra_cflags,
                 *include_flags(out_dir, self.description)]
        objects = compile_objects(compiler, flags, sources, out_dir / "obj", out_dir,
                                  self.description.toolchain.file_cflags)
        elf = out_dir / f"{program.name}.elf"
        # Every item, chart and device state stays in a simulation build, even
        # one no code reads: the harness traces it from RAM.
        keep = [f"-Wl,--undefined={s}" for s in kept_symbols(program, self.name) + [simulator.TICK_SYMBOL]] \
            if self.sim else []
        link = [compiler, f"-mmcu={self.part.name}", "-Os", "-o", str(elf), *map(str, objects),
                *self.description.toolchain.ldflags, *keep]
        proc = subprocess.run(link, capture_output=True, text=True)
        measured = elf
        if proc.returncode != 0:
            text = proc.stdout + proc.stderr
            if "not within region" not in text and "overflowed by" not in text:
                raise BuildError(f"linking with {compiler} failed:\n{text}".rstrip())
            # Too big for the part: link again into memories of any size, only
            # to measure by how much.
            measured = out_dir / f"{program.name}.oversize.elf"
            run(link[:4] + [str(measured)] + link[5:] + ["-Wl,--defsym=__DATA_REGION_LENGTH__=0xffa0",
                                                         "-Wl,--defsym=__TEXT_REGION_LENGTH__=0x400000"],
                "measuring link")
            if elf.exists():
                elf.unlink()
        report = self.size_report(measured)
        problem = None
        if report.flash > report.flash_max:
            problem = self._not_fit(program, "text", report.flash - report.flash_max, options)
        elif report.ram + STACK_RESERVE > self.part.ram:
            problem = self._not_fit(program, "data", report.ram + STACK_RESERVE - self.part.ram, options)
            problem += "\n" + self._ram_users(measured, objects)
        if measured != elf:
            measured.unlink()
        if problem is not None:
            if elf.exists():
                elf.unlink()
            raise BuildError("\n".join(report.lines) + "\n" + problem)
        hexfile = out_dir / f"{program.name}.hex"
        run([self._tool("objcopy", "avr-objcopy"), "-O", "ihex", "-R", ".eeprom", "-R", ".mmcu", "-R", ".fuse",
             "-R", ".lock", "-R", ".signature", str(elf), str(hexfile)], "avr-objcopy", _PACKAGES)
        return Compiled(elf, sources, report, image=hexfile)

    # ---------------------------------------------------------------- sizes

    def size_report(self, elf: Path) -> SizeReport:
        mcu = self.part
        s = elf_sections(self._tool("size", "avr-size"), elf, _PACKAGES)
        flash = s.get(".text", 0) + s.get(".data", 0)  # initialised data is stored in flash
        ram = s.get(".data", 0) + s.get(".bss", 0) + s.get(".noinit", 0)
        flash_max = mcu.flash - mcu.bootloader
        line = (f"{mcu.name}: flash {flash} of {flash_max} bytes ({100.0 * flash / flash_max:.1f} %"
                + (f", {mcu.flash} minus {mcu.bootloader} for the bootloader" if mcu.bootloader else "") + "), "
                f"RAM {ram} of {mcu.ram} bytes ({100.0 * ram / mcu.ram:.1f} %, static data; the stack uses the rest)")
        return SizeReport(flash, ram, flash_max, mcu.ram, [line])

    def _ram_users(self, elf: Path, objects: list[Path], top: int = 6) -> str:
        """The biggest variables in RAM, with the file each comes from."""
        nm = self._tool("nm", "avr-nm")
        owner: dict[str, str] = {}
        for obj in objects:
            out = subprocess.run([nm, "--defined-only", str(obj)], capture_output=True, text=True).stdout
            for line in out.splitlines():
                parts = line.split()
                if len(parts) == 3 and parts[1] in "bBdDrR":
                    owner.setdefault(parts[2], obj.stem.removesuffix("_gen") + ".c")
        syms = sorted(((size, name) for name, (_addr, size) in simulator.ram_symbols(nm, elf).items() if size),
                      reverse=True)
        return "largest in RAM: " + ", ".join(f"{name} {size} B ({owner.get(name, '?')})" for size, name in syms[:top])

    def _not_fit(self, program: Program, region: str, over: int, options: CompileOptions) -> str:
        mcu = self.part
        if region == "text":
            msg = (f"error: the program does not fit the {mcu.name}'s flash ({mcu.flash - mcu.bootloader} bytes "
                   f"for programs): {over} bytes too many")
        else:
            msg = (f"error: the program does not fit the {mcu.name}'s {mcu.ram} bytes of RAM: {over} bytes too many "
                   f"(static data plus {STACK_RESERVE} bytes kept for the stack)")
            buffered = [df for df in program.dataflows if df.buffers]
            if buffered and options.schedule != "min-buffer":
                def buffer_bytes(df) -> int:
                    return sum(b.size * max(1, (getattr(b.type, "bits", 8) or 8) // 8) for b in df.buffers)
                biggest = max(buffered, key=buffer_bytes)
                msg += (f"; dataflow '{biggest.name}' ({biggest.schedule_kind} schedule) keeps "
                        f"{buffer_bytes(biggest)} bytes of tokens: try --schedule min-buffer (smaller buffers, a "
                        f"longer schedule)")
            if not options.release and any(i.kind == "debug" for i in program.interfaces):
                size = "a few hundred bytes" if self.model_sized_debug_buffers else "about 1 KB"
                msg += f"; the debug interface's buffers take {size}: a --release build has none"
        size = (lambda m: m.flash) if region == "text" else (lambda m: m.ram)
        bigger = [m for m in self.all_mcus.values() if size(m) > size(mcu)]
        if bigger:
            msg += f"; or build for --mcu {bigger[0].name}"
        return msg

    # ---------------------------------------------------------------- running, flashing

    def build_simulator(self, program: Program, checked: object, out_dir: Path, compiled: Compiled) -> Simulator:
        exe = simulator.build_harness(self, out_dir, simulator.sim_model_source(program, self, compiled.executable),
                                      out_dir / f"{program.name}-sim", chip_files(program, self.name))
        return Simulator(exe, simulator.simulation_warnings(program, self))

    def simulator_command(self, out_dir: Path, program: Program) -> list[str]:
        """The harness with every UART of the part on a pty in ``out_dir``."""
        links = [arg for n in sorted(self.part.uart) for arg in (f"--uart{n}", f"pty:{out_dir / f'uart{n}'}")]
        return [str(out_dir / f"{program.name}-sim"), *links]

    def flash_command(self, out_dir: Path, program: Program, port: str, programmer: str | None = None,
                      baud: int | None = None) -> list[str]:
        """avrdude through the bootloader (no fuses are touched)."""
        template = self.description.table("flash").get(
            "command", "avrdude -p {part} -c {programmer} -P {port} -b {baud} -D -U flash:w:{hex}:i")
        mcu = self.part
        return shlex.split(template.format(part=mcu.avrdude_part, programmer=programmer or mcu.programmer, port=port,
                                           baud=baud or mcu.upload_baud, hex=out_dir / f"{program.name}.hex"))

    def run_port_program(self, source: Path, work_dir: Path) -> str:
        """The program on the MCU in simavr; its report comes on USART0."""
        t = devices.tick_timer(1000, self.clock_hz)
        write_files(work_dir, {
            "el_avr_config.h": "\n".join([
                f"#define EL_AVR_CONFIG_VERSION {devices.CONFIG_VERSION}",
                f"#define EL_AVR_MCU_NAME \"{self.part.name}\"", f"#define EL_AVR_NV_SIZE {self.part.eeprom}u",
                f"#define EL_AVR_TICK_PRESCALE {t.prescale}u", f"#define EL_AVR_TICK_CS {t.cs}u",
                f"#define EL_AVR_TICK_OCR {t.ocr}u", f"#define EL_AVR_TICK_ISRS {t.isrs}u",
                f"#define EL_AVR_CLOCK_KHZ {self.clock_hz // t.prescale // 1000}u", "#define EL_AVR_WDTO WDTO_2S", ""]),
            "el_avr_devices.h": "/* no devices */\n"})
        elf = work_dir / f"{source.stem}.elf"
        chain = self.description.toolchain
        # The port's files with their own options, as a firmware compiles them.
        objects = compile_objects(chain.cc, [*self.cflags, *mode_flags(True), *include_flags(work_dir, self.description)],
                                  [source, *(p for p in self.description.source_paths if p.name != "avr_interfaces.c")],
                                  work_dir / "obj", file_flags=chain.file_cflags)
        run([chain.cc, f"-mmcu={self.part.name}", "-Os", "-o", str(elf), *map(str, objects), *chain.ldflags],
            f"building {source.name} for the {self.part.name}", _PACKAGES)
        harness = simulator.build_harness(self, work_dir, simulator.port_program_tables(self, elf),
                                          work_dir / f"{source.stem}-sim")
        report = work_dir / "uart0.txt"
        proc = subprocess.run([str(harness), "--fast", "--uart0", f"file:{report}", "--cycles", "100000000"],
                              capture_output=True, text=True, timeout=120, stdin=subprocess.DEVNULL)
        if proc.returncode != 0:
            raise BuildError(f"the simulation of {source.name} failed: {proc.stderr.strip()}")
        return report.read_text()

    def symbols(self, compiled: Compiled) -> set[str]:
        return set(simulator.ram_symbols(self._tool("nm", "avr-nm"), compiled.executable)) | \
            super().symbols(compiled)
