"""The register map (generator/servicegen.py): tables, stable automatic and
explicit addresses, clashes, the map files beside the firmware and the
generated C tables."""

from __future__ import annotations

import csv
import io
import json
import subprocess
import sys

import pytest

from svc_testlib import EXAMPLES

MODEL = """model m "Map test"
param a: int16 = 1 range 0..10 unit "mm" service rw persist
param b: int32 = -2 service rw @ 1
param c: uint8 = 3 service rw
param d: float32 = 0.5 range -1.0..1.0 service rw
param e: time = 2 s service rw
param hidden: int16 = 0
var f: bool service rw
var g: bool service ro
var h: uint32 service ro @ 7
var i: int8 service ro
"""


def lower(tmp_path, text: str, name: str = "m.elab"):
    from easylab.pipeline import lower_file
    path = tmp_path / name
    path.write_text(text)
    program, result = lower_file(str(path))
    assert program is not None, result.report()
    return program


def test_tables_and_addresses(shim, tmp_path):
    from easylab.codegen import service as servicegen
    smap = servicegen.build_map(lower(tmp_path, MODEL))
    got = {e.name: (e.id, e.table, e.address, e.registers) for e in smap.entries}
    assert got == {
        "a": (0, "holding", 0, 1),
        "b": (1, "holding", 1, 2),       # explicit: 1..2
        "c": (2, "holding", 3, 1),       # the next free address after a, past b
        "d": (3, "holding", 4, 2),
        "e": (4, "holding", 6, 2),
        "f": (5, "coil", 0, 1),
        "g": (6, "discrete", 0, 1),
        "h": (7, "input", 7, 2),
        "i": (8, "input", 0, 1),
    }
    assert "hidden" not in got


def test_automatic_addresses_are_stable(shim, tmp_path):
    from easylab.codegen import service as servicegen
    before = {e.name: e.address for e in servicegen.build_map(lower(tmp_path, MODEL)).entries}
    more = MODEL + "param z: int32 = 0 service rw\nvar y: bool service rw\n"
    after = {e.name: e.address for e in servicegen.build_map(lower(tmp_path, more, "m2.elab")).entries}
    assert {k: after[k] for k in before} == before
    assert after["z"] == 8 and after["y"] == 1


def test_clashes_are_build_errors_naming_both(shim, tmp_path, tool_env):
    model = tmp_path / "clash.elab"
    model.write_text("model clash\nparam a: int32 = 0 service rw @ 10\nparam b: int16 = 0 service rw @ 11\n")
    proc = subprocess.run([sys.executable, "-m", "easylab", "build", str(model), "--board", "host", "-o",
                           str(tmp_path / "out")], capture_output=True, text=True, env=tool_env, timeout=120)
    assert proc.returncode == 1
    # The checker reports the clash with the source line (the map builder
    # checks again, for what the checker cannot see).
    assert proc.stderr.startswith(f"{model}:3:20: error: holding register 11 of 'b' overlaps 'a' (10..11)\n")
    from easylab.codegen import service as servicegen
    with pytest.raises(servicegen.ServiceMapError, match="runs past 65535"):
        servicegen.build_map(lower(tmp_path, "model x\nparam a: int32 = 0 service rw @ 65535\n", "x.elab"))
    many = "model y\n" + "".join(f"param p{k}: int16 = 0 service rw persist\n" for k in range(205))
    with pytest.raises(servicegen.ServiceMapError, match="205 persist params need 4100 bytes"):
        servicegen.build_map(lower(tmp_path, many, "y.elab"), nv_size=4096)


def test_map_files(shim, tmp_path):
    from easylab.board.registry import load_board
    from easylab.codegen import render as cgen, service as servicegen
    from easylab.core.paths import templates_dir
    program = lower(tmp_path, MODEL + "modbus tcp port 1502\nmodbus rtu on uart1 baud 9600 parity odd unit 9\n")
    files = cgen.render(program, load_board("host"), templates_dir())
    assert files == cgen.render(program, load_board("host"), templates_dir())   # deterministic
    doc = json.loads(files["service_map.json"])
    assert doc["model"] == "m" and doc["program_id"] == f"0x{program.program_id:08x}" and doc["word_order"] == "big"
    assert doc["interfaces"] == {"tcp": {"port": 1502, "unit": 1},
                                 "rtu": {"uart": "uart[1]", "baud": 9600, "parity": "odd", "unit": 9}}
    a = doc["items"][0]
    assert {k: a[k] for k in ("name", "table", "address", "type", "scale", "unit", "range", "access", "persist")} \
        == {"name": "a", "table": "holding", "address": 0, "type": "int16", "scale": 1, "unit": "mm",
            "range": [0, 10], "access": "rw", "persist": True}
    e = next(i for i in doc["items"] if i["name"] == "e")
    assert (e["unit"], e["registers"], e["initial"]) == ("ms", 2, 2000)
    rows = list(csv.DictReader(io.StringIO(files["service_map.csv"])))
    assert [r["name"] for r in rows] == ["a", "b", "c", "d", "e", "f", "g", "h", "i"]
    assert rows[3]["min"] == "-1.0" and rows[3]["table"] == "holding" and rows[0]["persist"] == "yes"
    md = files["service_map.md"]
    assert "| 1 | `b` | holding | 1 | 400002..400003 | int32 |" in md
    assert "Modbus RTU on uart[1]: 9600 baud, parity odd, unit 9" in md
    c = files["service_tables.c"]
    assert "el_port_mb_rtu_open(1u, 9600UL, EL_MB_PARITY_ODD, 9u)" in c
    assert "el_port_mb_tcp_open(1502u)" in c
    assert "0xbf800000UL, 0x3f800000UL" in c   # d's range -1.0..1.0 as float bits
    assert servicegen.crc16(b"123456789") == 0x4B37


def test_every_example_has_a_map(shim):
    from easylab.board.registry import load_board
    from easylab.codegen import render as cgen
    from easylab.core.paths import templates_dir
    from easylab.pipeline import lower_file
    for path in sorted(EXAMPLES.glob("*.elab")):
        program, result = lower_file(str(path))
        assert program is not None, result.report()
        files = cgen.render(program, load_board("host"), templates_dir())
        doc = json.loads(files["service_map.json"])
        assert [i["name"] for i in doc["items"]] == [i.name for i in program.items if i.service], path
        has_rtu = any(i.kind == "modbus-rtu" for i in program.interfaces)
        assert ("el_port_mb_rtu_open" in files["service_tables.c"]) == has_rtu


def test_service_stays_in_release_builds(builds, firmware):
    """Only debug code leaves a release build: Modbus is still served."""
    from svc_testlib import RawTcp
    b = builds("service_all", release=True)
    fw = firmware(b.exe, rtu=False)
    c = RawTcp(fw.port)
    try:
        assert c.ask(bytes([0x03, 0, 100, 0, 1])) == bytes([0x03, 2, 0, 7])
    finally:
        c.close()
