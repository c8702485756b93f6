"""The suite's test files by how long they take, so that `make test` can
start the longest first (pytest-xdist's `--dist loadfile` runs a file on one
process; a long file started last would leave the other processes idle).

    python tests/durations.py LOG   # LOG: the output of pytest --durations=N
    python tests/durations.py build/test-durations.json

updates tests/durations.json: seconds per test file (its tests' setup, call
and teardown as the report lists them). Files the report does not list
count DEFAULT_SECONDS. conftest.py orders the collection by it, and after
every run of the whole suite writes build/test-durations.json, every
file's seconds (RECORD), which this script takes as it is."""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path

TABLE = Path(__file__).with_name("durations.json")
DEFAULT_SECONDS = 5.0
RECORD = Path(__file__).resolve().parents[1] / "build" / "test-durations.json"
_LINE = re.compile(r"^(\d+(?:\.\d+)?)s (?:call|setup|teardown)\s+(\S+?)::")


def file_seconds(report: str) -> dict[str, float]:
    """Seconds per test file from the lines of a ``--durations`` report."""
    totals: dict[str, float] = {}
    for line in report.splitlines():
        m = _LINE.match(line.strip())
        if m:
            totals[m.group(2)] = totals.get(m.group(2), 0.0) + float(m.group(1))
    return totals


def load() -> dict[str, float]:
    """The table, or nothing when it is missing or unreadable (every file
    then counts the same: the order is pytest's)."""
    try:
        table = json.loads(TABLE.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return {str(k): float(v) for k, v in table.items()} if isinstance(table, dict) else {}


def main(argv: list[str]) -> int:
    if len(argv) != 1:
        print(__doc__.strip(), file=sys.stderr)
        return 2
    text = Path(argv[0]).read_text(encoding="utf-8", errors="replace")
    try:
        recorded = json.loads(text)
    except ValueError:
        recorded = None
    totals = ({str(k): float(v) for k, v in recorded.items()} if isinstance(recorded, dict)
              else file_seconds(text))
    if not totals:
        print(f"{argv[0]}: no --durations lines", file=sys.stderr)
        return 1
    table = {**load(), **totals}  # files the record does not list keep their figure
    TABLE.write_text(json.dumps({k: round(v) for k, v in sorted(table.items())}, indent=1) + "\n",
                     encoding="utf-8")
    print(f"{TABLE}: {len(totals)} files")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
