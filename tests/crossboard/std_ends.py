"""The models of the std actors at their arguments' ends (boundaries.py
writes them) as files, for the tests of every board (test_std_boundaries.py:
host board and local execution; test_std_boundaries_mcu.py: the MCU
boards' compilers)."""

from __future__ import annotations

from pathlib import Path

import pytest

from boundaries import INTEGERS, NUMBERS, model
from easylab.core import types as T

SMALL = [T.INT8, T.UINT8, T.INT16, T.UINT16]
WIDE = [T.INT32, T.UINT32, T.FLOAT32]
# A user actor: its parameter and its type decide both comparisons.
USER = """
actor type Band<T: integer>(low: T, high: T) {
    in  x: T
    out y: bool
    step {{ y = (x >= low) && (x <= high) && (x >= 0); }}
}
"""


def write(folder: Path, name: str, text: str) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{name}.elab"
    path.write_text(text, encoding="utf-8")
    return path


def user_model(name: str) -> str:
    """Band at the ends of every integer type, fed by a Ramp of the type."""
    lines = [f"model {name}", "import std", USER]
    body, k = [], 0
    for t in INTEGERS:
        body.append(f"    r_{t.name} = Ramp<{t.name}>(slope = {max(1, t.max // 8)})")
        for lo, hi in ((t.min, t.max), (0, 0), (t.max, t.min)):
            k += 1
            body += [f"    b{k} = Band<{t.name}>(low = ({lo}), high = ({hi}))", f"    r_{t.name}.y -> b{k}.x",
                     f"    b{k}.y -> o{k}"]
            lines.append(f"var o{k}: bool")
    lines += ["dataflow U {", *body, "}", "task main period 1 ms { run U }", ""]
    return "\n".join(lines)


# The actors whose C compares (or, as Select, met a 16-bit int's narrowing):
# what the MCU builds that cannot hold every actor keep.
COMPARING = {"Div", "Compare", "Hysteresis", "SquareWave", "MovingAverage", "Select", "Limit", "Counter"}


@pytest.fixture(scope="module")
def models(tmp_path_factory) -> dict[str, Path]:
    """The whole model (host, local execution); for the MCUs the same actors
    without a var per output ("mcu"), in halves of the types for the F16's
    C89 checks ("small", "wide"); the comparing actors in halves for the
    PIC18's RAM ("cmp_small", "cmp_wide") and per type for the 8051's 64 KB
    of code ("cmp_int8" ..); the user actor's model."""
    folder = tmp_path_factory.mktemp("ends")
    texts = {"all": model("ends_all", NUMBERS, big=True),
             "mcu": model("ends_mcu", NUMBERS, traced=False),
             "small": model("ends_small", SMALL, casts=False, others=False, traced=False),
             "wide": model("ends_wide", WIDE, traced=False),
             "cmp_small": model("ends_cmp_small", SMALL, casts=False, traced=False, only=COMPARING),
             "cmp_wide": model("ends_cmp_wide", WIDE, casts=False, others=False, traced=False, only=COMPARING),
             "user": user_model("ends_user")}
    for t in NUMBERS:
        texts[f"cmp_{t.name}"] = model(f"ends_cmp_{t.name}", [t], casts=False, others=t is T.INT8, traced=False,
                                       only=COMPARING)
    return {key: write(folder, f"ends_{key}", text) for key, text in texts.items()}
