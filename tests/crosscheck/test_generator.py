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
