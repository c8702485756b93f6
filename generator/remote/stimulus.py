"""A stimulus file split for remote execution (docs/remote.md): the host
board's proxy reads the device `out` columns, `easylab remote` the params
and vars."""

from __future__ import annotations

import csv
import io

from ..ir.program import Program


def device_columns(text: str, program: Program) -> str | None:
    """The time column and the device `out` columns of a stimulus CSV (the
    host board's format; ``name`` or ``name[i]`` headers), or None when it
    has no such column."""
    names = {i.name for i in program.items if i.kind == "dev_out"}
    rows = list(csv.reader(io.StringIO(text)))
    if not rows:
        return None
    keep = [0] + [k for k, name in enumerate(rows[0]) if k and name.split("[")[0].strip() in names]
    if len(keep) == 1:
        return None
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    for row in rows:
        writer.writerow([row[k] if k < len(row) else "" for k in keep])
    return out.getvalue()
