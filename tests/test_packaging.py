"""The wheel installs a working `easylab` that needs nothing from the source tree."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import venv
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _run(cmd, **kw):
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600, **kw)
    assert proc.returncode == 0, f"{cmd} failed:\n{proc.stdout}\n{proc.stderr}"
    return proc


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """A fresh virtual environment with the project installed from its wheel."""
    tmp = tmp_path_factory.mktemp("wheel")
    # Build from a copy so no build artefact lands in the work tree.
    src = tmp / "src"
    shutil.copytree(ROOT, src, ignore=shutil.ignore_patterns(".venv", "build", ".git", "__pycache__",
                                                             "*.egg-info", ".pytest_cache", ".hypothesis"))
    dist = tmp / "dist"
    built = _run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-v", "-w", str(dist),
                  str(src)])
    # Every folder of the package is declared (setup.py): setuptools has
    # nothing to warn about.
    chatter = built.stdout + built.stderr
    assert "would be ignored" not in chatter and "SetuptoolsDeprecationWarning" not in chatter, chatter[-3000:]
    wheels = list(dist.glob("easylab-*.whl"))
    assert len(wheels) == 1
    env_dir = tmp / "venv"
    venv.create(env_dir, with_pip=True)
    python = env_dir / "bin" / "python"
    _run([str(python), "-m", "pip", "install", "-q", str(wheels[0])])
    return env_dir, tmp


def test_wheel_checks_and_draws_an_example_outside_the_tree(installed):
    env_dir, tmp = installed
    work = tmp / "elsewhere"
    work.mkdir()
    model = work / "pt100_sensor.elab"
    shutil.copy(ROOT / "examples" / "pt100_sensor.elab", model)
    clean_env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH",)}
    exe = env_dir / "bin" / "easylab"
    out = _run([str(exe), "check", model.name], cwd=work, env=clean_env)
    assert "pt100_sensor.elab: ok" in out.stdout
    if shutil.which("dot"):
        _run([str(exe), "graph", model.name, "-o", "pt100.svg"], cwd=work, env=clean_env)
        assert "Acquire" in (work / "pt100.svg").read_text()
    where = _run([str(env_dir / "bin" / "python"), "-c",
                  "import easylab, importlib.resources as r; print(easylab.__file__); "
                  "print(r.files('easylab.stdlib').joinpath('std.elab').is_file())"],
                 cwd=work, env=clean_env).stdout.split()
    assert str(env_dir) in where[0], "easylab must be imported from the installed wheel"
    assert where[1] == "True"
    # The installed package builds firmware from its own runtime and boards.
    out = _run([str(exe), "build", model.name, "--board", "host", "-o", "fw"], cwd=work, env=clean_env)
    program = work / out.stdout.strip().splitlines()[-1]
    assert program.is_file() and program.parent == work / "fw"
    # The installed boards are found and their backends load from the wheel.
    out = _run([str(exe), "boards"], cwd=work, env=clean_env)
    assert out.stdout.startswith("avr: ") and "\nhost: " in out.stdout


def test_wheel_carries_the_package_data(installed):
    env_dir, _ = installed
    site = next((env_dir / "lib").glob("python3*/site-packages/easylab"))
    for rel in ("frontend/elab.lark", "stdlib/std.elab", "stdlib/actors/pt100_linearize.c", "templates/model.c.j2",
                "templates/actor.c.j2", "runtime_c/el_dispatch.c", "runtime_c/el_debug_protocol.h",
                "boards/host/board.toml", "boards/host/host_port.c", "boards/avr/board.toml",
                "boards/avr/sim/avr_sim.c", "host_tools/debug_console.py", "interp/engine.py",
                # the harnesses' core, the chips on their buses and the std chip models
                "sim/sim_chips.c", "sim/sim_chips.h", "sim/el_chip.h", "sim/chips/tmp102.c", "sim/sim_harness.c",
                # local execution's interfaces library is built from these at run time
                "templates/interp_interfaces.c.j2", "boards/host/host_interp.c", "boards/host/host_load.c",
                "boards/host/host_serve.c", "interp/interfaces.py",
                # the boards' backends and the contract they implement
                "boards/host/backend.py", "boards/avr/backend.py", "boards/avr/devices.py", "board/contract.py",
                # the service panel's page, with uPlot and its licence
                "host_tools/web/server.py", "host_tools/web/static/index.html", "host_tools/web/static/panel.js",
                "host_tools/web/static/panel.css", "host_tools/web/static/vendor/uPlot.iife.min.js",
                "host_tools/web/static/vendor/uPlot.min.css", "host_tools/web/static/vendor/uPlot.LICENSE"):
        assert (site / rel).is_file(), rel


def test_wheel_serves_the_service_panel(installed, tmp_path):
    """The installed `easylab-service web` serves its page and uPlot from the
    wheel (no device needed to start)."""
    import json
    import re
    import signal
    import urllib.request

    env_dir, _ = installed
    smap = tmp_path / "service_map.json"
    smap.write_text(json.dumps({"format": 1, "model": "m", "program_id": "0x1", "interfaces": {}, "items": []}))
    clean_env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH",)}
    proc = subprocess.Popen([str(env_dir / "bin" / "easylab-service"), "--map", str(smap), "--tcp", "127.0.0.1:1",
                             "web", "--listen", "127.0.0.1:0"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, cwd=tmp_path, env=clean_env)
    try:
        url = re.search(r"http://\S+", proc.stdout.readline()).group(0)
        for path, marker in (("", "<title>EasyLab service panel</title>"), ("static/panel.js", "easylabPanel"),
                             ("static/vendor/uPlot.iife.min.js", "uPlot")):
            with urllib.request.urlopen(url + path, timeout=10) as r:
                assert marker in r.read().decode(), path
    finally:
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(timeout=15) == 0, proc.stderr.read()
