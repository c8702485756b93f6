"""The protocol's constants exist once, in runtime_c/el_debug_protocol.h:
the Python side must read exactly what a C compiler sees there."""

from __future__ import annotations

import re
import shutil
import subprocess

import pytest
from hypothesis import given, strategies as st

from debug_testlib import ROOT
from easylab.host_tools import debug_protocol as P

HEADER = ROOT / "runtime_c" / "el_debug_protocol.h"


@pytest.mark.skipif(shutil.which("gcc") is None, reason="needs gcc -E")
def test_pycparser_reads_the_same_constants_from_the_c_header(tmp_path):
    from pycparser import c_ast, c_parser

    names = re.findall(r"^#define (EL_DBG_\w+) ", HEADER.read_text(), re.M)
    assert len(names) == len(P.CONSTANTS) > 80
    probe = tmp_path / "probe.c"
    probe.write_text(f'#include "{HEADER}"\n'
                     + "".join(f"unsigned long long {n[len('EL_DBG_'):]}_ = {n};\n" for n in names))
    text = subprocess.run(["gcc", "-E", "-P", str(probe)], capture_output=True, text=True, check=True).stdout
    ast = c_parser.CParser().parse(text)

    def value(node):
        if isinstance(node, c_ast.Constant):
            return int(node.value.rstrip("uUlL"), 0)
        if isinstance(node, c_ast.Cast):
            return value(node.expr)
        raise AssertionError(f"not an integer constant: {node}")

    seen = {decl.name[:-1]: value(decl.init) for decl in ast.ext}
    assert seen == P.CONSTANTS


def test_every_request_and_error_is_documented():
    doc = (ROOT / "docs" / "protocol.md").read_text()
    for name, value in P.CONSTANTS.items():
        if name.startswith(("CMD_", "E_")):
            assert f"`{name}`" in doc and f"0x{value:02x}" in doc.lower() or f"`{name}` ({value})" in doc, name


def test_the_c_runtime_and_the_python_side_agree_on_item_types():
    model_h = (ROOT / "runtime_c" / "el_model.h").read_text()
    for name, (code, _) in P.TYPES.items():
        c_name = {"bool": "BOOL", "int8": "I8", "uint8": "U8", "int16": "I16", "uint16": "U16", "int32": "I32",
                  "uint32": "U32", "float32": "F32", "time": "TIME"}[name]
        assert re.search(rf"EL_T_{c_name} = {code}\b", model_h), name


@given(st.binary(max_size=600))
def test_cobs_round_trips_and_never_contains_the_delimiter(data):
    enc = P.cobs_encode(data)
    assert 0 not in enc and len(enc) <= len(data) + 1 + len(data) // 254
    assert P.cobs_decode(enc) == data


@given(st.integers(0, 255), st.integers(0, 127), st.binary(max_size=P.K.MAX_PAYLOAD))
def test_frames_round_trip(seq, cmd, payload):
    wire = P.encode_frame(seq, cmd, payload)
    assert wire.endswith(b"\x00") and wire.count(0) == 1
    assert len(wire) <= P.max_encoded(P.K.MAX_FRAME)
    assert P.decode_frame(wire[:-1]) == (seq, cmd, payload)


def test_crc_is_crc16_modbus():
    assert P.crc16(b"123456789") == 0x4B37
