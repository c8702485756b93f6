"""The host board's backend (board.toml names it): the firmware as a POSIX
process with simulated devices. Its program is its own simulation: it runs
in real or virtual time, reads a stimulus and writes traces
(boards/host/README.md)."""

from __future__ import annotations

import subprocess
from pathlib import Path

from easylab.board import handlers
from easylab.board.base import BoardBase
from easylab.board.cbuild import (elf_sections, include_flags, mode_flags, require_tool, run, runtime_sources)
from easylab.board.contract import Compiled, CompileOptions, SizeReport, Simulator
from easylab.core.errors import BuildError
from easylab.ir.program import Device, Program

from . import dds


class HostBoard(BoardBase):
    """Every resource claim is accepted (a process has no pins to run out
    of); a device runs the host handlers its type brings from the model's
    folder, else the simulated driver of el_board.h (stimulus in, trace
    out)."""

    has_simulator = True

    def device_call(self, device: Device, handler: str) -> str:
        model = handlers.call(device, handler, self.name)
        if model is None:
            return f"el_sim_{handler}({device.id}u);"
        if handler == "read":  # the handler starts from the stimulus due now (docs/language.md)
            return f"el_sim_sample({device.id}u); {model}".rstrip()
        return model

    def check(self, program: Program) -> object:
        """Every claim and every device goes (a device without host handlers
        is simulated); the handler files the build uses must be readable."""
        handlers.check_files(program, self.name)
        return None

    def compile(self, program: Program, checked: object, out_dir: Path, generated: list[Path],
                options: CompileOptions) -> Compiled:
        chain = self.description.toolchain
        compiler = options.cc or chain.cc
        require_tool(compiler, self.name, chain.debian_package if compiler == chain.cc else None)
        dds_sources, dds_cflags, dds_libs = dds.build_files(program, out_dir, self.description.folder)
        sources = [p for p in generated if p.suffix == ".c"] + runtime_sources(options.release) \
            + self.description.source_paths + dds_sources
        exe = out_dir / program.name
        cmd = [compiler, *chain.cflags, *mode_flags(options.release), *options.extra_cflags, *dds_cflags,
               *include_flags(out_dir, self.description), "-o", str(exe), *map(str, sources), *chain.ldflags,
               *dds_libs]
        proc = subprocess.run(cmd, capture_output=True, text=True)
        if proc.returncode != 0:
            raise BuildError(f"{compiler} failed:\n{proc.stdout}{proc.stderr}".rstrip())
        return Compiled(exe, sources, self._size(exe))

    def _size(self, exe: Path) -> SizeReport:
        s = elf_sections(self.description.toolchain.tool("size", "size"), exe, "binutils")
        code = s.get(".text", 0) + s.get(".rodata", 0)
        data = s.get(".data", 0) + s.get(".bss", 0)
        return SizeReport(code, data, None, None,
                          [f"host: code {code} bytes, static data {data} bytes (a process: no limits)"])

    def build_simulator(self, program: Program, checked: object, out_dir: Path, compiled: Compiled) -> Simulator:
        return Simulator(compiled.executable)

    def simulator_command(self, out_dir: Path, program: Program) -> list[str]:
        """The program in real time, its debug link (if any) on a pty."""
        debug = ["--debug", f"pty:{out_dir / 'debug'}"] if any(i.kind == "debug" for i in program.interfaces) else []
        return [str(out_dir / program.name), *debug]

    def run_port_program(self, source: Path, work_dir: Path) -> str:
        chain = self.description.toolchain
        exe = work_dir / source.stem
        sources = [source, *runtime_sources(True, exclude=("el_dispatch.c",)), *self.description.source_paths]
        run([chain.cc, *chain.cflags, *mode_flags(True), *include_flags(None, self.description), "-o", str(exe),
             *map(str, sources), *chain.ldflags], f"building {source.name} for the host board")
        proc = subprocess.run([str(exe)], capture_output=True, text=True, timeout=120, stdin=subprocess.DEVNULL)
        return proc.stdout
