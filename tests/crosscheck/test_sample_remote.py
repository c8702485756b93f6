"""Back-to-back: the suite's fixed-seed sample of random models in remote
execution's lock-step, with a host-board proxy and with an AVR proxy in
simavr, against local execution (sample.py; docs/testing.md)."""

import pytest

from sample import SAMPLE, assert_same_trace

CASES = [(mode, seed) for mode in ("remote-host", "remote-avr") for seed in range(1, SAMPLE[mode] + 1)]


@pytest.mark.parametrize("mode, seed", CASES)
def test_random_model_gives_local_executions_trace(mode, seed, tmp_path):
    assert_same_trace(seed, mode, tmp_path)
