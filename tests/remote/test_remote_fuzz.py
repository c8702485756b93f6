"""libFuzzer over the proxy's frame decoding and handling
(fuzz/remote_fuzz.c: runtime_c/el_remote.c on a model of two devices and
two tasks), under ASan and UBSan: at least 100,000 executions from the
valid frames of fuzz/remote_corpus/ without a finding, every frame the
proxy sends well formed and the safe values held after STOP. Twice: with
the frame buffers the model's sizes (fuzz/remote_include/el_remote_config.h:
longer frames take the decoder's oversize path) and with the protocol's
largest.

Inputs are capped at 512 bytes: four records of the largest size, or a
few hundred one-byte instants. Longer inputs only repeat instants (each
record is one), and made the target five times slower for no new
coverage (docs/testing.md, "Fuzzing")."""

from __future__ import annotations

import pytest

from fuzzing import FUZZ, RUNTIME, run_fuzzer


@pytest.mark.parametrize("largest", [False, True], ids=["model-sized", "largest"])
def test_fuzz_proxy_frames(largest, tmp_path):
    run_fuzzer(tmp_path, "remote_fuzz",
               [FUZZ / "remote_fuzz.c", FUZZ / "remote_fuzz_model.c",
                *(RUNTIME / f for f in ("el_remote.c", "el_debug_cobs.c", "el_crc16.c"))],
               "remote_corpus", cflags=("-DEL_REMOTE_PROXY=1", f"-DEL_FUZZ_LARGEST_FRAMES={int(largest)}"),
               includes=(FUZZ / "remote_include",), args=("-max_len=512",))
