"""Back-to-back testing on random models (docs/testing.md).

    python tests/crosscheck/crosscheck.py -n 50 --boards host,avr,pic18 [--seed 1000] [--out DIR] [--jobs 2]
    make crosscheck N=50 BOARDS=host,avr,pic18

For each seed a model and a stimulus are generated for each part the
chosen modes need (modelgen.py); local execution gives the reference trace
and every other mode must give the same bytes. A mode that finds the model
too large for its part skips it (counted); a build that fails otherwise,
a run that fails, a sanitizer report or another trace is a finding: the
model, its stimulus and both traces are kept in DIR/findings/, shrunk to a
small model with ``shrink.py``. The last line is the summary per mode.

With ``--ledger FILE`` every result is also appended to FILE (one JSON
line: seed, part, mode, verdict, the commit and the generator's digest),
and a result already there for the same seed, mode and generator is not
run again unless it was a finding: a campaign of thousands of models
accumulates over several runs (``--tally FILE`` prints its figures)."""

from __future__ import annotations

import argparse
import hashlib
import json
import re
import subprocess
import sys
from collections import Counter, defaultdict
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
GENERATOR_FILES = ("modelgen.py", "actors_gen.py", "charts_gen.py", "ctypes_gen.py", "parts_gen.py")

from modelgen import Options, generate  # noqa: E402
from modes import MODES, Outcome  # noqa: E402


@dataclass
class Case:
    """A model and its stimulus on disk."""

    name: str
    model: Path
    stimulus: Path
    duration_ms: int


def write_case(folder: Path, name: str, text: str, stimulus: str, duration_ms: int) -> Case:
    folder.mkdir(parents=True, exist_ok=True)
    model = folder / f"{name}.elab"
    model.write_text(text)
    stim = folder / f"{name}.stimulus.csv"
    stim.write_text(read_columns(model, stimulus))
    return Case(name, model, stim, duration_ms)


def read_columns(model: Path, stimulus: str) -> str:
    """The stimulus without the columns of devices no task reads: every
    mode refuses those (board/stimulus_columns.py), and the generator's
    stimuli name every device datum. Nothing else changes: such a device
    never samples, in any mode."""
    from easylab.board.stimulus_columns import unread_items
    from easylab.pipeline import lower_file

    program, _ = lower_file(model)
    if program is None:
        return stimulus
    unread = {program.items[i].name for i in unread_items(program)}
    rows = [line.split(",") for line in stimulus.splitlines()]
    if not rows or not unread:
        return stimulus
    keep = [k for k, col in enumerate(rows[0]) if col.split("[", 1)[0] not in unread]
    return "".join(",".join(row[k] for k in keep) + "\n" for row in rows)


def first_difference(a: bytes, b: bytes) -> str:
    """Where two CSV traces part: the header and the first differing rows."""
    la, lb = a.decode(errors="replace").splitlines(), b.decode(errors="replace").splitlines()
    for i, (x, y) in enumerate(zip(la, lb)):
        if x != y:
            return f"line {i + 1}:\n  header    {la[0]}\n  reference {x}\n  mode      {y}"
    return f"lengths differ: {len(la)} and {len(lb)} lines"


def signature(verdict: str, detail: str) -> str:
    """What identifies a finding: 'differs', or the first error line without paths and numbers."""
    if verdict == "differs":
        return verdict
    error = next((ln for ln in detail.splitlines() if re.search(r"error|runtime|Caught|did not", ln)),
                 detail[:200])
    return verdict + ": " + re.sub(r"\S*/|\b[0-9a-f]{12,}\b|\d+", "", error).strip()


def compare(case: Case, work: Path, modes: list[str]) -> dict[str, tuple[str, str]]:
    """mode -> (verdict, detail) for one case: ``equal``, ``differs``,
    ``skip``, ``fail``; the reference (local execution) is ``reference``
    or ``fail``."""
    reference = MODES["local"][1](case, work)
    results: dict[str, tuple[str, str]] = {}
    if reference.status != "trace":
        results["local"] = ("fail", reference.detail)
        return results
    results["local"] = ("reference", "")
    for mode in modes:
        if mode == "local":
            continue
        try:
            outcome: Outcome = MODES[mode][1](case, work)
        except Exception as exc:  # a timeout, a crashed harness: a finding, reported
            outcome = Outcome("fail", detail=f"{type(exc).__name__}: {exc}")
        if outcome.status != "trace":
            results[mode] = (outcome.status, outcome.detail)
        elif outcome.trace == reference.trace:
            results[mode] = ("equal", "")
        else:
            (work / f"{mode}.trace.csv").write_bytes(outcome.trace)
            (work / "local.trace.csv").write_bytes(reference.trace)
            results[mode] = ("differs", first_difference(reference.trace, outcome.trace))
    return results


def generator_digest() -> str:
    """What the models of a seed depend on: the generator's sources."""
    h = hashlib.sha256()
    for name in GENERATOR_FILES:
        h.update((HERE / name).read_bytes())
    return h.hexdigest()[:12]


def current_commit() -> str:
    """The project's commit (``-dirty`` when the tree has changes), or ``unknown``."""
    def git(*args):
        return subprocess.run(["git", *args], cwd=HERE, capture_output=True, text=True).stdout.strip()
    commit = git("rev-parse", "--short=12", "HEAD") or "unknown"
    return commit + ("-dirty" if git("status", "--porcelain", "--untracked-files=no") else "")


class Ledger:
    """Results kept across runs (one JSON object a line); ``done`` tells
    whether a seed's result in a mode was already obtained, with this
    generator, and was not a finding."""

    def __init__(self, path: Path | None):
        self.path, self.generator, self.commit = path, generator_digest(), current_commit()
        self.entries = read_ledger(path) if path and path.is_file() else []
        self._done = {(e["seed"], e["mode"]) for e in self.entries
                      if e["generator"] == self.generator and e["verdict"] in ("equal", "skip", "reference")}

    def done(self, seed: int, mode: str) -> bool:
        return (seed, mode) in self._done

    def add(self, seed: int, part: str, mode: str, verdict: str) -> None:
        if self.path is None:
            return
        entry = {"seed": seed, "part": part, "mode": mode, "verdict": verdict, "commit": self.commit,
                 "generator": self.generator}
        with self.path.open("a") as f:
            f.write(json.dumps(entry) + "\n")


def read_ledger(path: Path) -> list[dict]:
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]


def ledger_tally(entries: list[dict], generator: str | None = None) -> dict[str, Counter]:
    """mode -> verdict counts of one generator's models (this one's by
    default: another generator's seed is another model), the latest result
    of each seed counting once (a finding run again after its fix counts as
    what it gives now)."""
    generator = generator or generator_digest()
    latest: dict[tuple, str] = {}
    for e in entries:
        if e["generator"] == generator:
            latest[(e["generator"], e["seed"], e["part"], e["mode"])] = e["verdict"]
    tally: dict[str, Counter] = defaultdict(Counter)
    for (_, _, _, mode), verdict in latest.items():
        tally[mode][verdict] += 1
    return tally


def campaign(seeds: range, modes: list[str], out: Path, jobs: int, options: Options,
             ledger: Ledger | None = None) -> dict:
    """Every seed in every mode; the tally and the findings."""
    ledger = ledger or Ledger(None)
    parts = defaultdict(list)
    for mode in modes:
        parts[MODES[mode][0]].append(mode)
    jobs_list = [(seed, part, todo) for seed in seeds for part, part_modes in parts.items()
                 if (todo := [m for m in part_modes if not ledger.done(seed, m)])]

    def one(job):
        seed, part, part_modes = job
        generated = generate(seed, part, options)
        work = out / "work" / f"{generated.name}-{part}"
        case = write_case(work, generated.name, generated.text, generated.stimulus, generated.duration_ms)
        return seed, part, case, compare(case, work, part_modes)

    tally: dict[str, Counter] = defaultdict(Counter)
    findings = []
    with ThreadPoolExecutor(max_workers=jobs) as pool:
        for seed, part, case, results in pool.map(one, jobs_list):
            for mode, (verdict, detail) in results.items():
                tally[mode][verdict] += 1
                ledger.add(seed, part, mode, verdict)
                if verdict in ("differs", "fail"):
                    findings.append({"seed": seed, "part": part, "mode": mode, "verdict": verdict,
                                     "model": str(case.model), "detail": detail})
                    print(f"seed {seed} ({part}) {mode}: {verdict}\n{detail}\n", flush=True)
    summary = {"seeds": [seeds.start, seeds.stop], "modes": modes,
               "tally": {m: dict(c) for m, c in tally.items()}, "findings": findings}
    (out / "summary.json").write_text(json.dumps(summary, indent=1))
    return summary


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("-n", type=int, default=20, help="models per part (default 20)")
    ap.add_argument("--seed", type=int, default=1, help="first seed (default 1)")
    ap.add_argument("--boards", default="host", help=f"comma-separated modes among {', '.join(MODES)} "
                    "(local execution, the reference, always runs)")
    ap.add_argument("--out", default="build/crosscheck", help="folder for models, traces and summary.json")
    ap.add_argument("--jobs", type=int, default=2, help="models run at once (default 2)")
    ap.add_argument("--floats", action="store_true", help="float32 among the numeric types")
    ap.add_argument("--ledger", type=Path, help="append every result to this file; results already in it "
                    "(same seed, mode and generator, not a finding) are not run again")
    ap.add_argument("--tally", type=Path, metavar="LEDGER", help="print a ledger's figures per mode and exit")
    args = ap.parse_args(argv)
    if args.tally:
        if not args.tally.is_file():
            ap.error(f"{args.tally}: no such ledger")
        entries = read_ledger(args.tally)
        for mode, counts in sorted(ledger_tally(entries).items()):
            print(f"{mode:12s} " + ", ".join(f"{k} {v}" for k, v in sorted(counts.items())))
        for other, count in sorted(Counter(e["generator"] for e in entries
                                           if e["generator"] != generator_digest()).items()):
            print(f"(and {count} results of an earlier generator, {other}: other models, not counted)")
        return 0
    modes = [m.strip() for m in args.boards.split(",") if m.strip()]
    unknown = [m for m in modes if m not in MODES]
    if unknown:
        ap.error(f"unknown mode(s) {', '.join(unknown)}: choose among {', '.join(MODES)}")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    summary = campaign(range(args.seed, args.seed + args.n), modes, out, args.jobs, Options(floats=args.floats),
                       Ledger(args.ledger))
    for mode, counts in summary["tally"].items():
        print(f"{mode:12s} " + ", ".join(f"{k} {v}" for k, v in sorted(counts.items())))
    kinds = Counter(f"{f['mode']}: {signature(f['verdict'], f['detail'])}" for f in summary["findings"])
    for kind, count in kinds.most_common():
        print(f"{count:5d}  {kind[:160]}")
    bad = len(summary["findings"])
    print(f"{bad} finding(s); details in {out / 'summary.json'}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
