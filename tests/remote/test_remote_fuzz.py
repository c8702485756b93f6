"""libFuzzer over the proxy's frame decoding and handling
(fuzz/remote_fuzz.c: runtime_c/el_remote.c on a model of two devices and
two tasks), under ASan and UBSan: at least 100,000 executions from the
valid frames of fuzz/remote_corpus/ without a finding, every frame the
proxy sends well formed and the safe values held after STOP."""

from __future__ import annotations

from fuzzing import FUZZ, RUNTIME, run_fuzzer


def test_fuzz_proxy_frames(tmp_path):
    run_fuzzer(tmp_path, "remote_fuzz",
               [FUZZ / "remote_fuzz.c", FUZZ / "remote_fuzz_model.c",
                *(RUNTIME / f for f in ("el_remote.c", "el_debug_cobs.c", "el_crc16.c"))],
               "remote_corpus", cflags=("-DEL_REMOTE_PROXY=1",))
