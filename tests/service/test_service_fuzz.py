"""libFuzzer over the Modbus slave's RTU and TCP request parsers and the
persistence records (fuzz/modbus_fuzz.c), under ASan and UBSan, for at
least 100,000 executions from the corpus in fuzz/modbus_corpus/ (copied:
the run adds nothing to the tree)."""

from __future__ import annotations

from fuzzing import FUZZ, RUNTIME, run_fuzzer


def test_fuzz_modbus_parsers(tmp_path):
    run_fuzzer(tmp_path, "modbus_fuzz",
               [FUZZ / "modbus_fuzz.c", *(RUNTIME / f for f in ("el_modbus.c", "el_service.c", "el_persist.c",
                                                                "el_crc16.c"))],
               "modbus_corpus", args=("-max_len=700",))
