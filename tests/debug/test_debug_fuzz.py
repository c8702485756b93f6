"""libFuzzer over the debug server's frame decoding and request dispatch,
under ASan and UBSan: at least 100,000 executions without a finding."""

from __future__ import annotations

from fuzzing import FUZZ, ROOT, RUNTIME, run_fuzzer


def test_fuzz_frames_and_requests(tmp_path):
    run_fuzzer(tmp_path, "debug_fuzz",
               [FUZZ / "debug_fuzz.c", FUZZ / "debug_fuzz_model.c",
                *(RUNTIME / f for f in ("el_debug.c", "el_debug_cobs.c", "el_crc16.c")),
                ROOT / "boards" / "host" / "host_load.c"],  # local execution's model upload too
               "debug_corpus", cflags=("-DEL_DEBUG=1", "-DEL_DEBUG_BOARD_COMMANDS=1"),
               includes=(FUZZ / "debug_include",))
