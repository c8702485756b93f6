"""The f16 board's backend (boards/f16/, docs/boards.md "The F16 board"):
the board contract for the Fujitsu MB90F543, whose compiler (Softune's
fcc907s) does not run here.

- ``check``: every claim against the part (the shared check) and what this
  board adds: UART1 is the UART it drives, one interface per UART at a
  baud rate UART1 makes, no `persist` (the part has nothing to keep it in);
- ``produce``: the device tables, configuration and vectors (project.py);
- ``compile``: a self-contained Softune project (the sources, a Makefile
  with fcc907s / flnk907s), compiled here by the proxies (proxy.py): clang
  for MSP430 always (16-bit int; its objects give size estimates and
  symbols), gcc -std=c89 and clang-tidy with ``--check``;
- a simulation build (``--sim``) is the 16-bit proxy instead: the model on
  an 8051 in s51, whose runner writes the host board's trace files
  (simulator.py). Its devices are simulated, so it checks no claims.
"""

from __future__ import annotations

import shlex
from pathlib import Path

from easylab.board import resources
from easylab.board.base import BoardBase
from easylab.board.cbuild import mode_flags, runtime_sources
from easylab.board.contract import Compiled, CompileOptions, Simulator, SizeReport
from easylab.core.errors import BuildError
from easylab.core.paths import runtime_dir
from easylab.ir.program import Device, Program

from . import project, proxy, simulator
from .part import read_mcus, uart1_rate

_FRONT_END_DEFINES = ["-DEL_BOARD_STDINT"]


class F16Board(BoardBase):
    has_simulator = True

    def __init__(self, description):
        super().__init__(description)
        self.all_mcus = read_mcus(description.table("mcu"))
        self.drivers: dict[str, dict] = description.table("drivers")

    @property
    def nv_size(self) -> int | None:
        """The proxy keeps a store in RAM like the host board's; the part has none."""
        return simulator.PROXY_NV_SIZE if self.sim else None

    # ---------------------------------------------------------------- code

    def device_call(self, device: Device, handler: str) -> str:
        if self.sim:
            return f"el_sim_{handler}({device.id}u);"
        return super().device_call(device, handler)

    def check(self, program: Program) -> resources.Resolved | None:
        if self.sim:
            return None
        return resources.check(program, self.name, self.part.part(), self.drivers, self._board_problems)

    def _board_problems(self, program: Program, res: resources.Resolved) -> list[str]:
        mcu = self.part
        problems = []
        for it in program.items:
            if it.persist:
                problems.append(f"{it.location}: error: param '{it.name}' is persist, but the {mcu.name} has no "
                                f"storage a program can keep it in (no EEPROM, and its flash cannot be written "
                                f"while the program runs from it): drop persist for the {self.name} board")
        users: dict[int, list[str]] = {}
        for iface in program.interfaces:
            parsed = resources.parse_claim(iface.resource) if iface.resource else None
            if parsed and parsed[0] == "uart":
                users.setdefault(parsed[1], []).append(f"interface '{iface.kind.replace('-', ' ')}'")
        for dev in program.devices:
            for claim in dev.claims:
                parsed = resources.parse_claim(claim)
                if parsed and parsed[0] == "uart":
                    users.setdefault(parsed[1], []).append(f"device '{dev.path}'")
        for n, who in sorted(users.items()):
            where = resources.interface_location(program, "debug" if "interface 'debug'" in who else "modbus-rtu")
            lead = f"{where}: error: " if where else "error: "
            if n in mcu.uart and n not in mcu.driven_uarts:
                problems.append(f"{lead}{', '.join(who)} claims uart[{n}]: UART{n} of the {mcu.name} is another "
                                f"circuit than UART1 (UMC{n}, USR{n}, URD{n}), which the {self.name} board does not "
                                f"drive; use uart1")
            elif len(who) > 1:
                problems.append(f"{lead}uart[{n}] is claimed by {' and '.join(who)}: one UART carries one of them")
        for n, use in sorted(res.uarts.items()):
            if n in mcu.driven_uarts and "baud" in use:
                try:
                    uart1_rate(mcu, int(use["baud"]), f"uart[{n}] ({use['use']})")
                except BuildError as err:
                    where = resources.interface_location(program, use["use"]) if use["use"] in (
                        "debug", "modbus-rtu") else ""
                    problems.append(f"{where + ': ' if where else ''}error: {err}")
        return problems

    def produce(self, program: Program, checked: resources.Resolved | None, release: bool) -> dict[str, str]:
        if self.sim:
            return simulator.files(program)
        return project.files(program, self.part, checked, release)

    def check_link_baud(self, baud: int) -> None:
        """UART1 makes only some rates from the machine clock (part.py's
        usable_rates, whose divisors the generated el_f16_config.h holds)."""
        project.check_link_baud(self.part, baud)

    # ---------------------------------------------------------------- compile

    def compile(self, program: Program, checked: object, out_dir: Path, generated: list[Path],
                options: CompileOptions) -> Compiled:
        if options.cc is not None:
            raise BuildError(f"--cc: the {self.name} board's compiler is Softune's fcc907s; the proxies are fixed")
        if self.sim:
            from easylab.remote.proxy import PROXY_CFLAGS

            if set(PROXY_CFLAGS) <= set(options.extra_cflags):
                raise BuildError(f"the {self.name} board's simulation (the model on an 8051 in s51) has no UART for "
                                 f"a remote-execution proxy's link: build the proxy without --sim, a Softune project "
                                 f"(docs/remote.md, \"The F16 proxy\")")
            return self._compile_proxy(program, out_dir, generated, options)
        return self._compile_project(program, out_dir, generated, options)

    def _compile_project(self, program: Program, out_dir: Path, generated: list[Path],
                         options: CompileOptions) -> Compiled:
        """The Softune project, and the proxies over its files."""
        originals = [p for p in generated if p.suffix == ".c"] + runtime_sources(options.release) \
            + self.description.source_paths
        headers = sorted(runtime_dir().glob("*.h")) + sorted(p for d in self.description.include_paths
                                                             for p in d.glob("*.h"))
        headers = [h for h in headers if h.name != "port_contract_hooks.h"]
        sources = [out_dir / rel for rel in project.copy_sources(out_dir, originals, headers, out_dir)]
        (out_dir / "Makefile").write_text(project.makefile(program, self.part, self.description.raw,
                                                           [str(s.relative_to(out_dir)) for s in sources],
                                                           options.release, options.extra_cflags), encoding="utf-8")
        flags = [*_FRONT_END_DEFINES, *mode_flags(options.release), *options.extra_cflags, f"-I{out_dir}",
                 f"-I{out_dir / 'runtime'}", f"-I{out_dir / 'board'}"]
        objects = proxy.clang_objects(self, sources, flags, out_dir / "obj430", out_dir)
        notes = [f"proxy: clang --target=msp430 -std=c89 -pedantic-errors -Wall -Wextra -Werror: "
                 f"{len(sources)} files clean"]
        if options.check:
            proxy.gcc_check(self, sources, flags, out_dir / "objc89", out_dir)
            proxy.tidy_check(self, sources, flags)
            notes += [f"proxy: gcc -std=c89 -pedantic-errors -Wall -Wextra -Werror: {len(sources)} files clean",
                      f"proxy: clang-tidy {', '.join(self.description.table('proxy')['clang_tidy_checks'])} "
                      f"(16-bit int): no finding"]
        code, data = proxy.object_sizes(objects)
        mcu = self.part
        line = (f"{mcu.name}: flash about {code} of {mcu.flash} bytes, RAM about {data} of {mcu.ram} bytes (static "
                f"data; estimated with clang for MSP430, a 16-bit CPU: flnk907s's map has the part's own figures)")
        report = SizeReport(code, data, mcu.flash, mcu.ram, [line])
        if data > mcu.ram:
            raise BuildError(f"{line}\nerror: the program's static data does not fit the {mcu.name}'s {mcu.ram} bytes "
                             f"of RAM: {data - mcu.ram} bytes too many")
        defines = project.fcc_defines(options.release, options.extra_cflags).split()
        cc_line = " ".join(shlex.quote(a) for a in [self.description.toolchain.cc,
                                                      *(f.format(cpu=mcu.cpu) for f in self.description.toolchain.cflags),
                                                      *defines, "-I", ".", "-I", "runtime", "-I", "board", "-o",
                                                      "obj/model.obj", "model.c"])
        notes += [f"compiling for the {mcu.name} needs Softune (fcc907s, flnk907s), which does not run here: "
                  f"copy Softune's startup for the MB90540 series into the folder as start.asm, then "
                  f"`make -C {out_dir} SOFTUNE=C:/Softune`, which runs for each file, e.g. `{cc_line}`"]
        return Compiled(out_dir, sources, report, notes)

    def _compile_proxy(self, program: Program, out_dir: Path, generated: list[Path],
                       options: CompileOptions) -> Compiled:
        ihx = simulator.build_image(self, program, out_dir, generated, options.release)
        code, xram = proxy.sdcc_memory(ihx)
        line = (f"16-bit proxy (8051, sdcc): code {code} of 65536 bytes, external RAM {xram} of 65280 bytes (the "
                f"model on an 8051 in s51, not the {self.part.name})")
        sources = [p for p in generated if p.suffix == ".c"] + runtime_sources(options.release) \
            + simulator.proxy_sources(self)
        return Compiled(ihx, sources, SizeReport(code, xram, 65536, 65280, [line]))

    # ---------------------------------------------------------------- running, flashing

    def build_simulator(self, program: Program, checked: object, out_dir: Path, compiled: Compiled) -> Simulator:
        exe = simulator.build_runner(self, out_dir, simulator.run_model_source(program, self, compiled.executable),
                                     out_dir / f"{program.name}-sim")
        return Simulator(exe, [f"note: the 16-bit proxy runs the model and the runtime on an 8051 (sdcc, s51), not "
                               f"on the {self.part.name}; its devices are simulated, as on the host board"])

    def simulator_command(self, out_dir: Path, program: Program) -> list[str]:
        return [str(out_dir / f"{program.name}-sim")]

    def flash_command(self, out_dir: Path, program: Program, port: str, programmer: str | None = None,
                      baud: int | None = None) -> list[str]:
        raise BuildError(f"the {self.name} board is flashed from Windows: build {program.name}.mhx with Softune "
                         f"(make -C {out_dir}), then write it with Fujitsu's FLASH MCU Programmer for the F2MC-16LX "
                         f"(part {self.part.cpu}, asynchronous serial mode, on {port}); nothing here can drive it")

    def run_port_program(self, source: Path, work_dir: Path) -> str:
        """The port contract program on the 16-bit proxy (f16_port.c's logic
        over the 8051's hardware layer)."""
        return simulator.run_port_program(self, source, work_dir)

    def symbols(self, compiled: Compiled) -> set[str]:
        if self.sim:
            return proxy.sdcc_symbols(compiled.executable)
        return proxy.object_symbols(sorted((compiled.executable / "obj430").glob("*.o")))
