"""A schedule that is not single-appearance moves tokens through circular
buffers; one token at a time is an assignment, not a loop (a dataflow of
fifty rate-one edges written as loops of one took sdcc's pic16 port
minutes to compile: docs/boards.md, "What sdcc gets wrong"). The C is the
same whatever the board, and the trace is the single-appearance one."""

from __future__ import annotations

import re

from native_testlib import ROOT, build, run

# A transfer macro and its token count (its last argument).
TRANSFER = re.compile(r"EL_(?:RING_GET|RING_PUT|COPY)\(.*, (\d+)u\);")


def test_single_tokens_move_without_loops_and_the_trace_is_unchanged(tmp_path):
    schedule = "min-buffer"  # rings (a flat schedule's buffers are linear, its actors write in place)
    model, stimulus = ROOT / "examples" / "cd_to_dat.elab", ROOT / "examples" / "cd_to_dat.stimulus.csv"
    reference = run(build(model, tmp_path / "sas", schedule="sas"), tmp_path / "sas.csv", duration="40ms",
                    stimulus=stimulus if stimulus.exists() else None)
    exe = build(model, tmp_path / schedule, schedule=schedule)
    code = (tmp_path / schedule / "model.c").read_text()
    counts = [int(n) for n in TRANSFER.findall(code)]
    assert counts and min(counts) > 1, counts  # cd_to_dat's multi-rate edges move several at once
    assert re.search(r"\b(el_df\d+_b\d+)\[\1_(?:rd|wr)\]", code), "no single token moved by assignment"
    traced = run(exe, tmp_path / f"{schedule}.csv", duration="40ms",
                 stimulus=stimulus if stimulus.exists() else None)
    assert traced.trace_text == reference.trace_text
