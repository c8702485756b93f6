"""Benchmark of the service interface (docs/service.md):

- requests per second over Modbus TCP on the host board, loopback only,
  with 1 and with 8 clients at once (each a blocking request/reply loop,
  bounded in count and time); the request reads the 12 holding registers of
  tests/service/data/service_all.elab;
- the cost of answering a 125-register read, in CPU instructions counted
  by callgrind over the slave's request handler (el_mb_pdu, and the whole
  RTU and TCP paths with framing and CRC), on a map of 125 int16 items;
- the AVR flash taken by the slave (avr-gcc -Os, ATmega328P), when avr-gcc
  is there.

``main(out_dir)`` writes out_dir/service.json and prints a table.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import socket
import struct
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RUNTIME = ROOT / "runtime_c"
MODEL = ROOT / "tests" / "service" / "data" / "service_all.elab"
SLAVE_FILES = ["el_modbus.c", "el_service.c", "el_persist.c", "el_crc16.c"]
REQUEST = struct.pack(">BHH", 0x03, 0, 12)
DURATION_S = 2.0       # per measurement, at most
MAX_REQUESTS = 20000   # per client, at most


# ---------------------------------------------------------------- TCP round trips


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _client(port: int, stop_at: float, counts: list, k: int) -> None:
    s = socket.create_connection(("127.0.0.1", port), timeout=5)
    s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    n = 0
    try:
        while n < MAX_REQUESTS and time.monotonic() < stop_at:
            tid = n & 0xFFFF
            s.sendall(struct.pack(">HHHB", tid, 0, len(REQUEST) + 1, 1) + REQUEST)
            want, got = 7 + 2 + 24, b""
            while len(got) < want:
                chunk = s.recv(want - len(got))
                if not chunk:
                    raise ConnectionError("closed")
                got += chunk
            assert struct.unpack(">H", got[:2])[0] == tid and got[7] == 0x03
            n += 1
    finally:
        s.close()
    counts[k] = n


def _rate(port: int, clients: int, seconds: float) -> float:
    counts = [0] * clients
    start = time.monotonic()
    stop_at = start + seconds
    threads = [threading.Thread(target=_client, args=(port, stop_at, counts, k)) for k in range(clients)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=seconds + 30)
    return sum(counts) / (time.monotonic() - start)


def _build_firmware(work: Path) -> Path:
    sys.path.insert(0, str(_package_root(work)))
    from easylab.build import build
    from easylab.pipeline import lower_file
    program, result = lower_file(str(MODEL))
    if program is None:
        raise RuntimeError(result.report())
    return build(program, "host", work / "fw", release=True).executable


def _package_root(work: Path) -> Path:
    """A directory holding `easylab` (the installed one, or a shim of generator/)."""
    try:
        import easylab  # noqa: F401
        return Path(easylab.__file__).resolve().parents[1]
    except ImportError:
        shim = work / "pkg"
        (shim).mkdir(exist_ok=True)
        if not (shim / "easylab").exists():
            (shim / "easylab").symlink_to(ROOT / "generator")
        return shim


def tcp_rates(work: Path, seconds: float = DURATION_S) -> dict:
    exe = _build_firmware(work)
    port = _free_port()
    proc = subprocess.Popen([str(exe), "--modbus-tcp", str(port), "--duration", "120s"], stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE)
    try:
        deadline = time.monotonic() + 10
        while True:
            try:
                socket.create_connection(("127.0.0.1", port), timeout=0.2).close()
                break
            except OSError:
                if time.monotonic() > deadline or proc.poll() is not None:
                    raise RuntimeError("the firmware did not come up")
                time.sleep(0.02)
        return {"clients_1": _rate(port, 1, seconds), "clients_8": _rate(port, 8, seconds)}
    finally:
        proc.terminate()
        proc.wait(timeout=20)


# ---------------------------------------------------------------- callgrind

HARNESS = r"""
#include "el_crc16.h"
#include "el_model.h"
#include "el_modbus.h"
#include "el_service.h"
#include <string.h>

bool el_port_nv_read(uint16_t offset, void *data, uint16_t size) { (void)offset; memset(data, 0xFF, size); return true; }
bool el_port_nv_write(uint16_t offset, const void *data, uint16_t size) { (void)offset; (void)data; (void)size; return true; }

static int16_t values[125];
static el_svc_entry_t entries[125];
static uint16_t order[125];
static el_svc_nv_t nv[1];
static el_svc_map_t map;

void bench_pdu(uint8_t *req, uint8_t *resp);
void bench_rtu(el_mb_rtu_t *rtu);
void bench_tcp(uint8_t *adu);

__attribute__((noinline)) void bench_pdu(uint8_t *req, uint8_t *resp) { (void)el_mb_pdu(req, 5u, resp, false); }
__attribute__((noinline)) void bench_rtu(el_mb_rtu_t *rtu)
{
    static const uint8_t frame[8] = {1u, 3u, 0u, 0u, 0u, 125u, 0u, 0u};
    uint8_t f[8];
    uint16_t crc, i;
    memcpy(f, frame, 8);
    crc = el_crc16(f, 6u);
    f[6] = (uint8_t)(crc & 0xFFu);
    f[7] = (uint8_t)(crc >> 8);
    for (i = 0; i < 8u; i++)
        (void)el_mb_rtu_byte(rtu, f[i]);
    (void)el_mb_rtu_reply(rtu);
}
__attribute__((noinline)) void bench_tcp(uint8_t *adu)
{
    static const uint8_t req[12] = {0u, 1u, 0u, 0u, 0u, 6u, 1u, 3u, 0u, 0u, 0u, 125u};
    memcpy(adu, req, 12);
    (void)el_mb_tcp_reply(adu, 12u);
}

int main(void)
{
    uint8_t req[5] = {3u, 0u, 0u, 0u, 125u}, resp[EL_MB_PDU_MAX], adu[EL_MB_TCP_ADU_MAX];
    static el_mb_rtu_t rtu;
    uint16_t i;
    for (i = 0; i < 125u; i++) {
        values[i] = (int16_t)(i * 3);
        entries[i].name = "x";
        entries[i].addr = &values[i];
        entries[i].address = i;
        entries[i].type = EL_T_I16;
        entries[i].table = EL_SVC_HOLDING;
        entries[i].flags = EL_SVC_F_RW;
        order[i] = i;
    }
    map.entries = entries;
    map.count = 125u;
    map.order = order;
    map.first[EL_SVC_INPUT] = 125u;
    map.size[EL_SVC_HOLDING] = 125u;
    map.nv = nv;
    el_service_init(&map);
    el_mb_rtu_init(&rtu, 1u, true);
    bench_pdu(req, resp);
    bench_rtu(&rtu);
    bench_tcp(adu);
    return resp[0] == 3u && resp[1] == 250u ? 0 : 1;
}
"""


def callgrind_instructions(work: Path) -> dict:
    if shutil.which("valgrind") is None:
        return {"error": "valgrind is not installed (Debian: valgrind)"}
    src = work / "harness.c"
    src.write_text(HARNESS)
    exe = work / "harness"
    subprocess.run(["gcc", "-std=c99", "-O2", "-g", f"-I{RUNTIME}", str(src),
                    *[str(RUNTIME / f) for f in SLAVE_FILES], "-o", str(exe)], check=True, capture_output=True)
    out = {}
    for fn in ("bench_pdu", "bench_rtu", "bench_tcp"):
        cg = work / f"cg.{fn}"
        proc = subprocess.run(["valgrind", "--tool=callgrind", f"--toggle-collect={fn}",
                               f"--callgrind-out-file={cg}", str(exe)], capture_output=True, text=True)
        if proc.returncode != 0:
            return {"error": proc.stderr[-500:]}
        text = cg.read_text()
        m = re.search(r"^(?:summary|totals):\s*(\d+)", text, re.M)
        out[fn] = int(m.group(1)) if m else None
    return {"pdu_read_125": out["bench_pdu"], "rtu_read_125": out["bench_rtu"], "tcp_read_125": out["bench_tcp"]}


def avr_sizes(work: Path) -> dict:
    if shutil.which("avr-gcc") is None or shutil.which("avr-size") is None:
        return {}
    sizes = {}
    for f in SLAVE_FILES:
        obj = work / (f + ".o")
        subprocess.run(["avr-gcc", "-mmcu=atmega328p", "-Os", "-std=c99", f"-I{RUNTIME}", "-c", str(RUNTIME / f),
                        "-o", str(obj)], check=True, capture_output=True)
        text = subprocess.run(["avr-size", str(obj)], capture_output=True, text=True, check=True).stdout
        sizes[f] = int(text.splitlines()[1].split()[0])
    return sizes


def main(out_dir, tiny: bool = False) -> dict:
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        result = {
            "tcp_requests_per_s": tcp_rates(work, 0.2 if tiny else DURATION_S),
            "request": "03 read 12 holding registers, loopback, one request in flight per client",
            "instructions": callgrind_instructions(work),
            "avr_text_bytes": avr_sizes(work),
            "machine": {"cpus": os.cpu_count()},
        }
    (out_dir / "service.json").write_text(json.dumps(result, indent=2) + "\n")
    r = result["tcp_requests_per_s"]
    ins = result["instructions"]
    print("service interface (Modbus slave)")
    print(f"  TCP requests/s, 1 client        {r['clients_1']:10.0f}")
    print(f"  TCP requests/s, 8 clients       {r['clients_8']:10.0f}")
    if "error" in ins:
        print(f"  instructions: {ins['error']}")
    else:
        print(f"  instructions, 125-register read: el_mb_pdu {ins['pdu_read_125']}, RTU frame "
              f"{ins['rtu_read_125']}, TCP ADU {ins['tcp_read_125']}")
    for f, n in result["avr_text_bytes"].items():
        print(f"  AVR flash {f:<16} {n:6d} bytes")
    print(f"  written to {out_dir / 'service.json'}")
    return result


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "bench/results")
