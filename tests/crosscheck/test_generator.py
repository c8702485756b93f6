"""The random model generator itself (modelgen.py): reproducible, every
model it writes is one the checker accepts, and over a few dozen seeds it
covers what back-to-back testing needs (docs/testing.md)."""

from __future__ import annotations

import re

import pytest

from easylab.pipeline import check_file
from actors_gen import MULTIRATE, STD_SINGLE_RATE
from modelgen import generate
from parts_gen import PARTS

SEEDS = range(1, 41)


@pytest.fixture(scope="module")
def models():
    return {(seed, part): generate(seed, part) for seed in SEEDS for part in PARTS}


def test_a_seed_gives_the_same_model_and_stimulus():
    a, b = generate(7, "pic18f4620"), generate(7, "pic18f4620")
    assert (a.text, a.stimulus) == (b.text, b.stimulus)
    assert generate(8, "pic18f4620").text != a.text


@pytest.mark.parametrize("part", list(PARTS))
def test_the_checker_accepts_every_generated_model(models, part):
    for seed in SEEDS:
        result = check_file(f"rand{seed}.elab", text=models[seed, part].text)
        assert result.model is not None, f"seed {seed} ({part}):\n{result.report()}\n{models[seed, part].text}"


def test_the_models_cover_the_language(models):
    text = "\n".join(m.text for m in models.values())
    for kind in STD_SINGLE_RATE + MULTIRATE:
        assert re.search(rf"= {kind}\b", text), f"no {kind}"
    for device in ("DigitalIn", "DigitalOut", "AnalogIn", "Pt100", "PwmOut", "Motor", "Encoder", "I2cTemperature",
                   "I2cEepromLog", "SpiEepromLog"):
        assert f": {device}(" in text, f"no {device}"
    for t in ("int8", "uint8", "int16", "uint16", "int32", "uint32"):
        assert f"<{t}>" in text and f"actor type" in text
    needed = {
        "user actor types": r"^actor type U\d",
        "a rate above 1": r" rate [23]\b",
        "zero initial tokens": r" delay [1-9]\b",
        "listed initial tokens": r" delay \[",
        "a channel": r"^channel ch\d+: \w+ delay \d+",
        "a divergence": r"-> \(\w+, \w+\) when",
        "a convergence": r"transition \(\w+, \w+\) ->",
        "a timed guard": r"\.time [<>]=? \d+ ms",
        "an entry action": r"\{ entry ",
        "an exit action": r"exit \w+ = ",
        "a persistent param": r"^param .* persist",
        "a task offset": r" offset \d+ us",
        "a task deadline": r" deadline \d+ us",
        "a flat schedule": r"schedule flat",
        "a min-buffer schedule": r"schedule min-buffer",
        "a const": r"^const K\d+",
        "a boundary argument": r"= -2147483648\b|= 4294967295\b",
    }
    for what, pattern in needed.items():
        assert re.search(pattern, text, re.M), f"no {what}"
    feedback = [(a, b) for a, b in re.findall(r"^    a(\d+)\.\w+ -> a(\d+)\.\w+ delay", text, re.M) if int(a) >= int(b)]
    assert feedback, "no feedback cycle"


def test_the_stimulus_names_only_the_models_inputs(models):
    for (seed, part), m in models.items():
        header = m.stimulus.splitlines()[0].split(",")
        assert header[0] == "time_us"
        for column in header[1:]:
            name = column.split(".")[0]
            assert re.search(rf"^(param|var|device) {name}\b", m.text, re.M), (seed, part, column)


def test_every_uint32_expression_has_32_bits_where_long_has_64(tmp_path):
    """A u32 expression is uint32_t with gcc on x86-64, where `unsigned
    long` has 64 bits, as on the MCU boards, where it has 32: a quotient by
    a `uL` constant left as `unsigned long` compared 64-bit values on the
    host board and 32-bit ones on the PIC18 (seed 1204)."""
    import random
    import subprocess

    from ctypes_gen import ExprWriter

    operands = {"a": "uint8", "b": "int16", "c": "uint32", "d": "int32"}
    lines = ["#include <stdint.h>", "uint8_t a; int16_t b; uint32_t c; int32_t d;"]
    for seed in range(400):
        expr = ExprWriter(random.Random(seed), operands).u32(4)
        lines.append(f"_Static_assert(sizeof({expr}) == 4u, \"seed {seed}\");")
    src = tmp_path / "widths.c"
    src.write_text("\n".join(lines) + "\n")
    proc = subprocess.run(["gcc", "-std=c11", "-fsyntax-only", "-w", str(src)], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr[:2000]
