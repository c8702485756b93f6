"""libFuzzer over the debug server's frame decoding and request dispatch,
under ASan and UBSan: at least 100,000 executions without a finding."""

from __future__ import annotations

from fuzzing import FUZZ, ROOT, RUNTIME, run_fuzzer


import pytest

# The server as a model with every kind of item, chart and range compiles
# it, and as one without charts, items of several elements and ranges does
# (el_debug_config.h's switches, runtime_c/el_debug.c), nor forcing and
# conditional breakpoints, does: the code left is
# fuzzed on the same tables (their charts then answer E_ID, their arrays
# show one element, their ranges are not checked).
SERVERS = {
    "every feature": (),
    "no charts, arrays or ranges": ("-DEL_DBG_HAS_CHARTS=0", "-DEL_DBG_HAS_ARRAYS=0", "-DEL_DBG_RANGES_UNSIGNED=0",
                                    "-DEL_DBG_RANGES_SIGNED=0", "-DEL_DBG_RANGES_FLOAT=0",
                                    "-DEL_DBG_FORCE_SLOTS=0", "-DEL_DBG_COND_SLOTS=0"),
}


@pytest.mark.parametrize("server", SERVERS)
def test_fuzz_frames_and_requests(tmp_path, server):
    run_fuzzer(tmp_path, "debug_fuzz",
               [FUZZ / "debug_fuzz.c", FUZZ / "debug_fuzz_model.c",
                *(RUNTIME / f for f in ("el_debug.c", "el_debug_cobs.c", "el_crc16.c")),
                ROOT / "boards" / "host" / "host_load.c"],  # local execution's model upload too
               "debug_corpus", cflags=("-DEL_DEBUG=1", "-DEL_DEBUG_BOARD_COMMANDS=1", *SERVERS[server]),
               includes=(FUZZ / "debug_include",))
