"""The host board's build of a node's DDS exports and channel ends
(docs/distribution.md, "DDS"): their IDL from the IR (ir/dds.py), compiled
with Cyclone DDS's idlc, and the table host_dds.c works from. A program
without either gets none of it and does not link libddsc."""

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
    """(C sources, compiler flags, linker flags) of the node's exports and
    DDS channel ends; all empty for a program without them. BuildError
    naming the packages when Cyclone DDS is missing, or with idlc's message."""
    if not program.exports and not program.dds_channels:
        return [], [], []
    cflags, libs = _pkg_config("--cflags"), _pkg_config("--libs")
    if shutil.which("idlc") is None or cflags is None or libs is None:
        raise BuildError(f"node program '{program.name}': {_MISSING}")
    idl = out_dir / f"{TYPES}.idl"
    idl.write_text(idl_text([*program.exports, *program.dds_channels]))
    proc = subprocess.run(["idlc", "-o", str(out_dir), str(idl)], capture_output=True, text=True)
    if proc.returncode != 0:
        raise BuildError(f"idlc failed on {idl}:\n{proc.stdout}{proc.stderr}".rstrip())
    table = out_dir / "el_dds_table.c"
    table.write_text(table_c(program))
    return [out_dir / f"{TYPES}.c", table, board_folder / "host_dds.c"], ["-DEL_HOST_DDS=1", *cflags], libs


def table_c(program: Program) -> str:
    """el_dds_table.c: a row per export (first: an export's index is its
    row), then per channel end: topic, type, domain, sample and timing."""
    rows = [*program.exports, *program.dds_channels]
    n = len(rows)
    lines = [f"/* DDS topics of {program.name} (generated from the IR; docs/distribution.md). */",
             f'#include "{TYPES}.h"', '#include "host_dds.h"', ""]
    for k, e in enumerate(rows):
        lines.append(f"static {e.c_type} el_dds_sample{k}; /* {e.name}: {e.type_name} */")
    for k, e in enumerate(program.dds_channels, len(program.exports)):
        c_type, ch = e.value_type.c_name, e.channel
        if e.direction == "out":
            lines += [f"uint16_t el_ch{ch}_pull({c_type} *tokens, uint16_t n);",
                      f"static uint16_t el_dds_pull{k}(void *tokens, uint16_t n)",
                      f"{{\n    return el_ch{ch}_pull(({c_type} *)tokens, n);\n}}"]
        else:
            lines += [f"uint16_t el_ch{ch}_push(const {c_type} *tokens, uint16_t n);",
                      f"static uint16_t el_dds_push{k}(const void *tokens, uint16_t n)",
                      f"{{\n    return el_ch{ch}_push((const {c_type} *)tokens, n);\n}}"]
    lines += ["", f"const el_dds_topic_t el_dds_topics[{n}] = {{"]
    for k, e in enumerate(rows):
        sample = f"&el_dds_sample{k}, &el_dds_sample{k}.data, sizeof el_dds_sample{k}.data, {e.values}u"
        if k < len(program.exports):
            rest = "EL_DDS_EXPORT, " + sample + ", NULL, NULL, 0u, 0u, 0u"
        elif e.direction == "out":
            rest = "EL_DDS_CHANNEL_OUT, " + sample + f", el_dds_pull{k}, NULL, 0u, 0u, 0u"
        else:
            rest = "EL_DDS_CHANNEL_IN, " + sample + f", NULL, el_dds_push{k}, {e.delay_us}u, {e.first_us}u, " \
                f"{e.period_us}u"
        lines.append(f'    {{"{e.topic}", &{e.c_type}_desc, {e.domain}u, {rest}}},')
    lines += ["};", f"const uint8_t el_dds_topic_count = {n}u;",
              f"const int32_t el_dds_history_depth = {HISTORY_DEPTH};",
              f"dds_entity_t el_dds_participants[{n}];", f"dds_entity_t el_dds_endpoints[{n}];",
              f"int64_t el_dds_last_us[{n}];", ""]
    return "\n".join(lines)


__all__ = ["build_files", "table_c"]
