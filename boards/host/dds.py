"""The host board's build of a node's DDS exports (docs/distribution.md,
"DDS"): the exports' IDL from the IR (ir/dds.py), compiled with Cyclone
DDS's idlc, and the table host_dds.c publishes from. A program without
exports gets none of it and does not link libddsc."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

from easylab.core.errors import BuildError
from easylab.ir.dds import HISTORY_DEPTH, idl_text
from easylab.ir.program import Program

TYPES = "el_dds_types"  # idlc's output: el_dds_types.c and .h
_MISSING = ("exports over DDS need Eclipse Cyclone DDS (libddsc and idlc): install the Debian packages "
            "cyclonedds-dev and cyclonedds-tools (`make setup` does)")


def _pkg_config(*args: str) -> list[str] | None:
    """pkg-config's answer for CycloneDDS, None when it does not know it."""
    if shutil.which("pkg-config") is None:
        return None
    proc = subprocess.run(["pkg-config", *args, "CycloneDDS"], capture_output=True, text=True)
    return proc.stdout.split() if proc.returncode == 0 else None


def build_files(program: Program, out_dir: Path, board_folder: Path) -> tuple[list[Path], list[str], list[str]]:
    """(C sources, compiler flags, linker flags) of the node's exports; all
    empty for a program without exports. BuildError naming the packages
    when Cyclone DDS is missing, or with idlc's message."""
    if not program.exports:
        return [], [], []
    cflags, libs = _pkg_config("--cflags"), _pkg_config("--libs")
    if shutil.which("idlc") is None or cflags is None or libs is None:
        raise BuildError(f"node program '{program.name}': {_MISSING}")
    idl = out_dir / f"{TYPES}.idl"
    idl.write_text(idl_text(program.exports))
    proc = subprocess.run(["idlc", "-o", str(out_dir), str(idl)], capture_output=True, text=True)
    if proc.returncode != 0:
        raise BuildError(f"idlc failed on {idl}:\n{proc.stdout}{proc.stderr}".rstrip())
    table = out_dir / "el_dds_table.c"
    table.write_text(table_c(program))
    return [out_dir / f"{TYPES}.c", table, board_folder / "host_dds.c"], ["-DEL_HOST_DDS=1", *cflags], libs


def table_c(program: Program) -> str:
    """el_dds_table.c: each export's topic, type, domain and sample."""
    n = len(program.exports)
    lines = [f"/* DDS exports of {program.name} (generated from the IR; docs/distribution.md). */",
             f'#include "{TYPES}.h"', '#include "host_dds.h"', ""]
    for k, e in enumerate(program.exports):
        lines.append(f"static {e.c_type} el_dds_sample{k}; /* {e.kind} {e.name}: {e.type_name} */")
    lines += ["", f"const el_dds_export_t el_dds_exports[{n}] = {{"]
    for k, e in enumerate(program.exports):
        lines.append(f'    {{"{e.topic}", &{e.c_type}_desc, {e.domain}u, &el_dds_sample{k}, '
                     f"&el_dds_sample{k}.data, sizeof el_dds_sample{k}.data}},")
    lines += ["};", f"const uint8_t el_dds_export_count = {n}u;",
              f"const int32_t el_dds_history_depth = {HISTORY_DEPTH};",
              f"dds_entity_t el_dds_participants[{n}];", f"dds_entity_t el_dds_writers[{n}];", ""]
    return "\n".join(lines)


__all__ = ["build_files", "table_c"]
