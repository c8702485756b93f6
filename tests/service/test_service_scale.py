"""Engineering units: a scaled item (`unit "degC" scale 0.1`, docs/language.md)
from the language to the map files, `easylab-service` and `easylab-debug`:
the checker's rules with file:line:col, the scale in service_map.json/.csv/.md
and debug_map.json, values shown in engineering units (162.8 degC, not
1628) and typed back exactly, refused when not representable or out of
range (generated scales, types and values, hypothesis)."""

from __future__ import annotations

import csv
import io
import json
import re
import subprocess
import sys
from decimal import Decimal
from fractions import Fraction

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from svc_testlib import ROOT

LIMITS = {"int8": (-128, 127), "uint8": (0, 255), "int16": (-32768, 32767), "uint16": (0, 65535),
          "int32": (-2 ** 31, 2 ** 31 - 1), "uint32": (0, 2 ** 32 - 1)}

MODEL = """model scaled "Scaled items"
param offset: int16 = -25 range -500..500 unit "degC" scale 0.1 service rw
param gain:   uint32 = 4 unit "bar" scale 2.5 service rw
var   temp:   int16 = 1628 unit "degC" scale 0.1 service ro
var   plain:  int16 = 7 unit "0.1 degC" service ro

debug on uart0
modbus tcp port 1502
"""


def lower(tmp_path, text: str, name: str = "m.elab"):
    from easylab.pipeline import lower_file
    path = tmp_path / name
    path.write_text(text)
    program, result = lower_file(str(path))
    return program, result


def service_map_file(tmp_path, text: str):
    """The service map of a model, written and loaded as the tool loads it."""
    from easylab.codegen.service import build_map, map_json
    from easylab.host_tools.service_map import load_map
    program, result = lower(tmp_path, text)
    assert program is not None, result.report()
    path = tmp_path / "service_map.json"
    path.write_text(json.dumps(map_json(build_map(program))))
    return load_map(path), json.loads(path.read_text())


# ---------------------------------------------------------------- the language


@pytest.mark.parametrize("decl, where, message", [
    ("var t: float32 scale 0.1 service ro", "2:16", "a scale needs an integer type, and 't' is a float32"),
    ("var t: time scale 2 service ro", "2:13", "a scale needs an integer type, and 't' is a time"),
    ("var t: bool scale 2 service ro", "2:13", "a scale needs an integer type, and 't' is a bool"),
    ("var t: int16 scale 0", "2:14", "the scale of 't' is 0, outside 0.000000001..1000000"),
    ("var t: int16 scale 0.0", "2:14", "the scale of 't' is 0, outside 0.000000001..1000000"),
    ("var t: int16 scale 2e6", "2:14", "the scale of 't' is 2e+06, outside 0.000000001..1000000"),
    ("var t: int16 scale 1.0000000001", "2:14", "the scale of 't' has more than 9 decimals"),
    ("var t: int16 scale -1", "2:20", "unexpected '-': a scale is a positive decimal number, as in 'scale 0.1'"),
    ("var t: int16 scale \"0.1\"", "2:20", "unexpected '\"0.1\"': a scale is a positive decimal number"),
    ("var t: int16 scale ten service ro", "2:20", "unexpected 'ten': a scale is a positive decimal number"),
    ("var t: int16 scale", "2:19", "unexpected end of the file: a scale is a positive decimal number"),
    ("param t: int16 scale 0.1 = 4", "2:26", "unexpected '=': the initial value '= ...' comes right after the type"),
    ("var t: int16 scale 0.1 scale 0.2", "2:24", "attribute 'scale' given twice"),
])
def test_bad_scales_are_errors_at_their_place(shim, tmp_path, decl, where, message):
    program, result = lower(tmp_path, f"model m\n{decl}\n")
    assert program is None
    assert f"m.elab:{where}: error: {message}" in result.report()


def test_scale_stays_a_name_elsewhere(shim, tmp_path):
    program, result = lower(tmp_path, "model m\nparam scale: int16 = 2 scale 0.5 service rw\n")
    assert program is not None, result.report()
    assert program.items[0].name == "scale" and program.items[0].scale == "0.5"


def test_an_unscaled_model_keeps_its_program_id(shim, tmp_path):
    """No scale, no change: the IR dump (hashed into the program id) omits it."""
    from easylab.ir.program import to_json
    program, _ = lower(tmp_path, "model m\nvar t: int16 unit \"u\" service ro\n")
    assert "scale" not in to_json(program)["items"][0]


# ---------------------------------------------------------------- the map files


def test_the_scale_reaches_every_map_file(shim, tmp_path):
    from easylab.codegen.debug import debug_items, debug_map
    from easylab.codegen.service import build_map, map_csv, map_md
    smap, data = service_map_file(tmp_path, MODEL)
    by_name = {i["name"]: i for i in data["items"]}
    assert (by_name["temp"]["scale"], by_name["temp"]["unit"]) == (0.1, "degC")
    assert (by_name["gain"]["scale"], by_name["plain"]["scale"]) == (2.5, 1)
    assert by_name["offset"]["range"] == [-500, 500]  # stored units, as the device checks them
    program, _ = lower(tmp_path, MODEL)
    rows = {r["name"]: r for r in csv.DictReader(io.StringIO(map_csv(build_map(program))))}
    assert (rows["temp"]["scale"], rows["plain"]["scale"]) == ("0.1", "1")
    assert "| degC (x 0.1) |" in map_md(build_map(program))
    assert smap.item("temp").format(1628) == "162.8"
    assert smap.item("offset").describe_range() == "-50.0..50.0 degC"


def test_the_debug_map_carries_the_scale(shim, tmp_path):
    built = build(tmp_path)
    from easylab.host_tools.debug_map import DebugMap
    dmap = DebugMap.load(str(built / "debug_map.json"))
    assert dmap.by_name["temp"].scale.text() == "0.1"
    assert dmap.by_name["plain"].scale.is_one
    assert "scale" not in json.loads((built / "debug_map.json").read_text())["items"][
        dmap.by_name["plain"].id]


# ---------------------------------------------------------------- generated scales and values

SCALES = st.builds(lambda digits, decimals: Fraction(digits, 10 ** decimals),
                   st.integers(1, 999_999), st.integers(0, 9)).filter(lambda f: Fraction(1, 10 ** 9) <= f <= 10 ** 6 and f != 1)


def scale_source(scale: Fraction) -> str:
    """The scale as a modeller writes it: plain decimals, or an exponent."""
    text = format(Decimal(scale.numerator) / Decimal(scale.denominator), "f")
    return text if scale.denominator == 1 or scale.numerator % 7 else f"{Decimal(text):e}"


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(scale=SCALES, type_name=st.sampled_from(sorted(LIMITS)), data=st.data())
def test_scaled_values_round_trip_through_the_map(shim, tmp_path, scale, type_name, data):
    """A generated scale through the language and the map file: every stored
    value shows as its exact engineering value and reads back to itself;
    text between two stored values, or beyond the type, is refused."""
    smap, _ = service_map_file(tmp_path, f"model m\nparam p: {type_name} = 0 unit \"u\" scale "
                                         f"{scale_source(scale)} service rw\n")
    it = smap.item("p")
    assert it.scale.fraction == scale
    lo, hi = LIMITS[type_name]
    stored = data.draw(st.one_of(st.integers(lo, hi), st.sampled_from([lo, hi, 0])))
    shown = it.format(stored)
    assert Fraction(Decimal(shown)) == stored * scale  # exact, with the scale's decimals
    assert it.parse(shown) == stored
    assert it.parse(f" +{shown} " if not shown.startswith("-") else shown) == stored
    from easylab.host_tools.service_map import ValueError_
    between = Fraction(Decimal(shown)) + scale / 2
    with pytest.raises(ValueError_, match="not a multiple of the scale"):
        it.parse(format(Decimal(between.numerator) / Decimal(between.denominator), "f"))
    with pytest.raises(ValueError_, match=rf"does not fit 'p' \({type_name} x "):
        it.parse(it.format(hi + 1))
    with pytest.raises(ValueError_, match="is not a decimal number"):
        it.parse("0x10")


# ---------------------------------------------------------------- the tools against a firmware


def build(tmp_path):
    from svc_testlib import build_model
    model = tmp_path / "model" / "scaled.elab"
    model.parent.mkdir(parents=True, exist_ok=True)
    model.write_text(MODEL)
    return build_model(model, tmp_path / "host").out


@pytest.fixture
def scaled_fw(tmp_path, firmware, tool_env):
    out = build(tmp_path)
    fw = firmware(out / "scaled", rtu=False, extra=["--debug", f"tcp:{free_tcp_port()}"])
    fw.out = out
    return fw


def free_tcp_port() -> int:
    from svc_testlib import free_port
    return free_port()


def service(tool_env, smap, port, *args, expect=0):
    cmd = [sys.executable, "-m", "easylab.host_tools.service_cli", "--map", str(smap), "--tcp",
           f"127.0.0.1:{port}", *args]
    proc = subprocess.run(cmd, capture_output=True, text=True, env=tool_env, timeout=60)
    assert "Traceback" not in proc.stderr, proc.stderr
    assert proc.returncode == expect, (proc.returncode, proc.stdout, proc.stderr)
    return proc


def test_the_service_tool_reads_and_writes_engineering_units(scaled_fw, tool_env):
    smap = scaled_fw.out / "service_map.json"
    listed = {line.split()[0]: line.split() for line in
              service(tool_env, smap, scaled_fw.port, "list").stdout.splitlines()[1:]}
    assert listed["offset"][4:7] == ["degC", "0.1", "-50.0..50.0"]
    assert listed["gain"][4:6] == ["bar", "2.5"] and listed["plain"][4:6] == ["0.1", "degC"]
    out = service(tool_env, smap, scaled_fw.port, "read", "temp", "offset", "gain", "plain").stdout
    assert out.splitlines() == ["temp = 162.8 degC", "offset = -2.5 degC", "gain = 10.0 bar", "plain = 7 0.1 degC"]
    assert service(tool_env, smap, scaled_fw.port, "write", "--", "offset", "-12.3").stdout == "offset = -12.3 degC\n"
    assert service(tool_env, smap, scaled_fw.port, "write", "gain", "7.5").stdout == "gain = 7.5 bar\n"
    err = service(tool_env, smap, scaled_fw.port, "write", "offset", "1.25", expect=2).stderr
    assert "'offset': 1.25 is not a multiple of the scale 0.1: it cannot be stored exactly" in err
    err = service(tool_env, smap, scaled_fw.port, "write", "offset", "60", expect=1).stderr
    assert "60.0 is outside the range of 'offset' (-50.0..50.0 degC): the device refused it (exception 03)" in err
    err = service(tool_env, smap, scaled_fw.port, "write", "offset", "3276.8", expect=2).stderr
    assert "3276.8 does not fit 'offset' (int16 x 0.1: -3276.8..3276.7 degC)" in err
    # What the device holds: stored units (Modbus registers are unscaled).
    backup = scaled_fw.out / "params.json"
    service(tool_env, smap, scaled_fw.port, "backup", str(backup))
    assert json.loads(backup.read_text())["params"] == {"offset": -123, "gain": 3}
    service(tool_env, smap, scaled_fw.port, "restore", str(backup))
    assert service(tool_env, smap, scaled_fw.port, "read", "offset").stdout == "offset = -12.3 degC\n"


def test_the_debug_console_shows_and_writes_engineering_units(scaled_fw, tool_env):
    port = int(re.search(r"tcp:(\d+)", " ".join(scaled_fw.args)).group(1))

    def console(commands: str, expect: int = 0) -> str:
        cmd = [sys.executable, "-m", "easylab.host_tools.debug_console", "--map",
               str(scaled_fw.out / "debug_map.json"), f"socket://127.0.0.1:{port}", "-c", commands]
        proc = subprocess.run(cmd, capture_output=True, text=True, env=tool_env, timeout=60)
        assert "Traceback" not in proc.stderr, proc.stderr
        assert proc.returncode == expect, (proc.stdout, proc.stderr)
        return proc.stdout + proc.stderr

    assert console("read temp offset plain").splitlines() == ["temp = 162.8 degC", "offset = -2.5 degC", "plain = 7"]
    assert "offset := 4.2 degC" in console("write offset 4.2")
    assert console("read offset") == "offset = 4.2 degC\n"
    assert "offset: 4.25 is not a multiple of the scale 0.1: it cannot be stored exactly" in \
        console("write offset 4.25", expect=1)
    assert "offset: 99 is outside its range -50.0 degC..50.0 degC" in console("write offset 99", expect=1)
    assert re.search(r'temp\s+int16\s+var\s+rw unit "degC" scale 0.1', console("vars temp"))
    assert re.search(r'offset\s+int16\s+param\s+rw -50.0..50.0 unit "degC" scale 0.1', console("vars offset"))
