"""The fixed-seed sample of the back-to-back campaign that the test suite
runs (docs/testing.md): how many models per mode, and the check of one."""

from __future__ import annotations

from pathlib import Path

from crosscheck import compare, write_case
from modelgen import generate
from modes import MODES

# Seeds of the suite's sample: seeds 1..N per mode (the campaign's own
# runs start elsewhere, at --seed 1000 and beyond: docs/testing.md). The
# host's are split over two modules, so that two test processes share them.
SAMPLE = {"host": 16, "avr": 5, "pic18": 5, "f16": 4, "remote-host": 2, "remote-avr": 1}


def assert_same_trace(seed: int, mode: str, tmp_path: Path) -> None:
    """Model ``seed`` for ``mode``'s part: local execution's trace and the
    mode's are the same bytes (or the model does not fit the part)."""
    generated = generate(seed, MODES[mode][0])
    case = write_case(tmp_path, generated.name, generated.text, generated.stimulus, generated.duration_ms)
    results = compare(case, tmp_path, [mode])
    assert results["local"][0] == "reference", f"{case.model}: local execution failed:\n{results['local'][1]}"
    verdict, detail = results[mode]
    assert verdict in ("equal", "skip"), f"{case.model} in {mode}: {verdict}\n{detail}"
