"""Fixtures of the service interface's tests: host builds of the examples and
of tests/service/data models, firmware processes serving Modbus TCP and RTU
on ptys, raw Modbus frames.

The tests need ``easylab.host_tools``: an installed (or editable) easylab
has it; with only a shim of generator/ on the path (``easylab`` ->
generator/), this conftest extends the package with a shim of its own
(tmp/easylab/host_tools -> host_tools/) and gives subprocesses a PYTHONPATH
holding both.
"""

from __future__ import annotations

import importlib.util
import os
import sys
from pathlib import Path

import pytest

from svc_testlib import (DATA, EXAMPLES, MCU_NO_TCP, ROOT, SIM_MCUS, Built, Firmware, InterpFirmware, McuFirmware,
                         build_interp, build_model, build_sim)
SANITIZE = "-g -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer"

# ---------------------------------------------------------------- packaging shim

_SHIM: Path | None = None


def _ensure_host_tools(tmp_root: Path) -> Path:
    """A directory whose ``easylab`` package has every module of generator/
    and host_tools: for subprocesses (PYTHONPATH) and for this process."""
    global _SHIM
    if _SHIM is not None:
        return _SHIM
    shim = tmp_root / "pkg"
    pkg = shim / "easylab"
    pkg.mkdir(parents=True, exist_ok=True)
    for entry in (ROOT / "generator").iterdir():
        link = pkg / entry.name
        if not link.exists():
            link.symlink_to(entry)
    if not (pkg / "host_tools").exists():
        (pkg / "host_tools").symlink_to(ROOT / "host_tools")
    if importlib.util.find_spec("easylab") is None:
        sys.path.insert(0, str(shim))
    import easylab
    if importlib.util.find_spec("easylab.host_tools") is None:
        easylab.__path__.append(str(pkg))
    _SHIM = shim
    return shim


@pytest.fixture(scope="session")
def shim(tmp_path_factory) -> Path:
    return _ensure_host_tools(tmp_path_factory.mktemp("shim"))


@pytest.fixture(scope="session")
def tool_env(shim) -> dict:
    """The environment of subprocesses running easylab and easylab-service."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(shim)] + [p for p in env.get("PYTHONPATH", "").split(os.pathsep) if p])
    env.setdefault("ASAN_OPTIONS", "detect_leaks=0")
    return env


# ---------------------------------------------------------------- builds


# The boards the Modbus RTU conformance tests run on: the host board's
# process (RTU on a pty), the AVR firmware (ATmega2560) in simavr and the
# PIC18 firmware (PIC18F4620) in gpsim with the model's Modbus UART on a
# pty, local execution. A test runs on all with @on_boards (svc_testlib),
# on the host only with @host_only(reason).
@pytest.fixture(scope="session")
def board(request) -> str:
    """The board of builds, svc_all and firmware (host unless parametrised)."""
    return getattr(request, "param", "host")


def pytest_collection_modifyitems(items):
    """Modbus TCP (a `tcp` parameter of a client or link fixture) is host-only."""
    for item in items:
        cs = getattr(item, "callspec", None)
        if cs is not None and cs.params.get("board") in SIM_MCUS and "tcp" in cs.params.values():
            item.add_marker(pytest.mark.skip(reason=MCU_NO_TCP))


@pytest.fixture(scope="session")
def builds(shim, tool_env, board, tmp_path_factory):
    d = tmp_path_factory.mktemp("service_builds")

    def get(name: str, cflags: str = "", release: bool = False) -> Built:
        model = DATA / f"{name}.elab" if (DATA / f"{name}.elab").exists() else EXAMPLES / f"{name}.elab"
        if board in SIM_MCUS:  # sanitizers are the host's; a debug build (release: no debug server, same Modbus)
            return build_sim(board, model, d / name, tool_env)
        if board == "interp":
            return build_interp(model, d / f"{name}_interp")
        tag = name + ("_asan" if cflags else "") + ("_rel" if release else "")
        return build_model(model, d / tag, cflags, release)
    return get


@pytest.fixture(scope="session")
def svc_all(builds) -> Built:
    """tests/service/data/service_all.elab with ASan and UBSan (host), or its
    MCU simulation build without Modbus TCP."""
    return builds("service_all", SANITIZE)


# ---------------------------------------------------------------- processes

@pytest.fixture
def firmware(tmp_path, board):
    """Start firmwares (host processes, or MCU harnesses); every one is
    stopped (and checked) at the end."""
    started: list[Firmware] = []

    def start(exe, **kw) -> Firmware:
        kind = McuFirmware if board in SIM_MCUS else (InterpFirmware if board == "interp" else Firmware)
        fw = kind(exe, tmp_path, **kw).start()
        started.append(fw)
        return fw
    yield start
    for fw in started:
        fw.stop()


