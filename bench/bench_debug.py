"""Benchmark of the debug protocol: bytes on the wire and round trips for
reading 1 and 32 variables, what that costs at 115200 baud (10 bits per
byte), and the round-trip time measured over a pty against a host build.
Prints a table and writes ``<out_dir>/debug.json``.

    python bench/bench_debug.py [out_dir]     (default: bench/results)
"""

from __future__ import annotations

import json
import os
import statistics
import struct
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

if __package__ in (None, ""):  # a script from a source checkout
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from source_checkout import make_easylab_importable

    make_easylab_importable()

from easylab.host_tools.debug_protocol import K, DebugClient, crc16, cobs_encode, encode_frame  # noqa: E402

BAUD = 115200
BITS_PER_BYTE = 10
N_VARS = 32

MODEL = """model bench_debug "32 variables for the debug benchmark"
actor type Count() {
    out y: int32
    state n: int32
    step {{ n = n + 1; y = n; }}
}
%s
dataflow D {
    c = Count()
    c.y -> v0
}
task main period 1 ms { run D }
debug on uart0 baud 115200
"""


def _response_wire(payload: bytes) -> int:
    """Bytes on the wire of a response (seq, cmd, status, payload, CRC)."""
    body = bytes([1, K.CMD_READ | K.RESPONSE, K.OK]) + payload
    crc = crc16(body)
    return len(cobs_encode(body + bytes([crc & 0xFF, crc >> 8]))) + 1


def wire_figures(n: int, size: int) -> dict:
    """Bytes and round trips to read n variables of `size` bytes each."""
    per_frame = (K.MAX_PAYLOAD - 1) // size  # values that fit in one response
    requests, req_bytes, resp_bytes = 0, 0, 0
    left = n
    while left > 0:
        k = min(left, per_frame)
        req_bytes += len(encode_frame(1, K.CMD_READ, b"".join(struct.pack("<H", i) for i in range(k))))
        resp_bytes += _response_wire(bytes(range(1, 1 + k * size)) if k * size < 255 else bytes(k * size))
        requests += 1
        left -= k
    total = req_bytes + resp_bytes
    return {"variables": n, "value_bytes": size, "round_trips": requests, "request_bytes": req_bytes,
            "response_bytes": resp_bytes, "total_bytes": total,
            "ms_at_115200": round(total * BITS_PER_BYTE / BAUD * 1000, 3)}


def measure(out_dir: Path, iterations: int = 300) -> dict:
    """Round-trip times over a pty against a host build with 32 int32 vars."""
    from easylab.build import build
    from easylab.pipeline import lower_file

    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        model = tmp / "bench_debug.elab"
        model.write_text(MODEL % "\n".join(f"var v{i}: int32" for i in range(N_VARS)))
        program, result = lower_file(model)
        assert program is not None, result.report()
        exe = build(program, "host", tmp / "build").executable
        link = tmp / "debug.pty"
        proc = subprocess.Popen([str(exe), "--debug", f"pty:{link},halt"], stderr=subprocess.PIPE)
        try:
            deadline = time.monotonic() + 10
            while not link.exists():
                if time.monotonic() > deadline:
                    raise RuntimeError("the benchmark firmware did not start")
                time.sleep(0.01)
            c = DebugClient.open(str(link), timeout=2.0)
            c.hello()
            items = [(i, "int32", 1) for i in range(N_VARS)]
            result = {}
            for n in (1, N_VARS):
                c.read(items[:n])  # warm up
                out_before, in_before = c.t.bytes_out, c.t.bytes_in
                rt_before = c.round_trips
                times = []
                for _ in range(iterations):
                    t0 = time.perf_counter()
                    c.read(items[:n])
                    times.append(time.perf_counter() - t0)
                result[f"read_{n}"] = {
                    "round_trips": (c.round_trips - rt_before) // iterations,
                    "bytes_out": (c.t.bytes_out - out_before) // iterations,
                    "bytes_in": (c.t.bytes_in - in_before) // iterations,
                    "pty_median_ms": round(statistics.median(times) * 1000, 3),
                    "pty_p95_ms": round(sorted(times)[int(0.95 * len(times))] * 1000, 3),
                }
            c.close()
        finally:
            proc.terminate()
            proc.wait(timeout=10)
    return result


def main(out_dir: str | Path = "bench/results", tiny: bool = False) -> dict:
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    wire = {"read_1_int16": wire_figures(1, 2), "read_1_int32": wire_figures(1, 4),
            f"read_{N_VARS}_int16": wire_figures(N_VARS, 2), f"read_{N_VARS}_int32": wire_figures(N_VARS, 4)}
    measured = measure(out_dir, iterations=5 if tiny else 300)
    results = {"baud": BAUD, "bits_per_byte": BITS_PER_BYTE, "max_frame": K.MAX_FRAME,
               "protocol_version": K.PROTOCOL_VERSION, "wire": wire, "measured_pty": measured}
    (out_dir / "debug.json").write_text(json.dumps(results, indent=1) + "\n")
    print(f"Debug protocol v{K.PROTOCOL_VERSION}, frames up to {K.MAX_FRAME} bytes, {BAUD} baud "
          f"({BITS_PER_BYTE} bits per byte)")
    print(f"{'read':<22}{'round trips':>12}{'request B':>11}{'response B':>12}{'total B':>9}{'ms @115200':>12}")
    for name, w in wire.items():
        print(f"{name:<22}{w['round_trips']:>12}{w['request_bytes']:>11}{w['response_bytes']:>12}"
              f"{w['total_bytes']:>9}{w['ms_at_115200']:>12.2f}")
    print(f"\nmeasured over a pty against a host build (int32 vars, {os.cpu_count()} cpus):")
    print(f"{'read':<22}{'round trips':>12}{'bytes out':>11}{'bytes in':>12}{'median ms':>11}{'p95 ms':>9}")
    for name, m in measured.items():
        print(f"{name:<22}{m['round_trips']:>12}{m['bytes_out']:>11}{m['bytes_in']:>12}{m['pty_median_ms']:>11.3f}"
              f"{m['pty_p95_ms']:>9.3f}")
    return results


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "bench/results")
