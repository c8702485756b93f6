"""Back-to-back: the suite's fixed-seed sample of random models in mode
'host', the first half of its seeds, against local execution (sample.py; docs/testing.md)."""

import pytest

from sample import SAMPLE, assert_same_trace


@pytest.mark.parametrize("seed", range(1, SAMPLE["host"] // 2 + 1))
def test_random_model_gives_local_executions_trace(seed, tmp_path):
    assert_same_trace(seed, "host", tmp_path)
