"""Device `state` fields (examples/pt100_logger: the TMP102 type's `state
reads: uint16`, which its handlers count) are read-only debug items
(`board_temp.reads`), read over a real pty by the client and the console,
a write refused by the firmware's server and by the console; and
`--trace-state` adds them to the trace of the host firmware and of local
execution alike."""

from __future__ import annotations

import shutil
import subprocess
import sys

import pytest

from debug_testlib import EXAMPLES, Firmware, InterpFirmware, build, env_with_tools
from easylab.host_tools.debug_protocol import K, DebugError

LOGGER = EXAMPLES / "pt100_logger"


@pytest.fixture(scope="module")
def logger(tmp_path_factory):
    """pt100_logger with a debug interface, and its host build."""
    folder = tmp_path_factory.mktemp("logger") / "pt100_logger"
    shutil.copytree(LOGGER, folder)
    model = folder / "pt100_logger.elab"
    model.write_text(model.read_text() + "debug on uart0 baud 115200\n")
    return model, build(model, folder / "host")


def _counts(fw, c, n: int) -> list[int]:
    """board_temp.reads at the first n halts at the start of task statistics."""
    m = fw.map
    reads = m.item("board_temp.reads")
    task = next(t["id"] for t in m.tasks if t["name"] == "statistics")
    c.bp_set(K.P_TASK, task)
    seen = []
    for _ in range(n):
        c.run()
        fw.wait_halted(c, 30)
        seen += c.read([(reads.id, reads.type, reads.count)])
    return seen


def _console(fw, command: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "easylab.host_tools.debug_console", "--map", str(fw.map_path),
                           str(fw.link), "-c", command], capture_output=True, text=True, timeout=60,
                          env=env_with_tools())


@pytest.mark.parametrize("kind", [Firmware, InterpFirmware], ids=["host", "local"])
def test_a_device_state_is_read_and_not_written(logger, tmp_path, kind):
    model, exe = logger
    fw = kind(exe if kind is Firmware else model, tmp_path, "--stimulus", str(LOGGER / "pt100_logger.stimulus.csv"))
    try:
        m = fw.map
        item = m.item("board_temp.reads")
        assert (item.kind, item.type, item.count, item.writable) == ("dev_state", "uint16", 1, False)
        assert m.item("board_temp.failures").kind == "dev_state"
        c = fw.client()
        assert c.read([(item.id, "uint16", 1)]) == [0]  # halted before the first instant
        first, *rest = _counts(fw, c, 3)
        assert rest == [first + 1, first + 2]  # one good read per release of task statistics
        with pytest.raises(DebugError) as refused:  # the server refuses it
            c.write(item.id, "uint16", 7)
        assert refused.value.status == K.E_READ_ONLY
        c.close()
        fw.clients.remove(c)
        said = _console(fw, "read board_temp.reads")
        assert said.returncode == 0 and said.stdout.strip() == f"board_temp.reads = {first + 2}", said
        said = _console(fw, "write board_temp.reads 7")
        assert said.returncode != 0
        assert "board_temp.reads is read-only (a device's state: only its handlers change it)" in said.stderr, said
    finally:
        fw.stop()


def test_trace_state_gives_the_same_columns_on_the_host_and_in_local_execution(logger, tmp_path):
    model, exe = logger
    stim = LOGGER / "pt100_logger.stimulus.csv"
    args = ["--fast", "--duration", "3500ms", "--stimulus", str(stim)]
    host, local, plain = tmp_path / "host.csv", tmp_path / "local.csv", tmp_path / "plain.csv"
    subprocess.run([str(exe), *args, "--trace", str(host), "--trace-state"], check=True, timeout=120)
    subprocess.run([str(exe), *args, "--trace", str(plain)], check=True, timeout=120)
    subprocess.run([sys.executable, "-m", "easylab", "run", str(model), *args, "--trace", str(local),
                    "--trace-state"], check=True, timeout=300)
    assert local.read_bytes() == host.read_bytes()
    header, *rows = host.read_text().splitlines()
    names = header.split(",")
    assert names[-2:] == ["board_temp.reads", "board_temp.failures"]  # after the items (the model has no charts)
    assert plain.read_text().splitlines()[0] == ",".join(names[:-2])  # only with the option
    last = dict(zip(names, rows[-1].split(",")))
    assert (last["board_temp.reads"], last["board_temp.failures"]) == ("4", "0")  # releases at 0, 1, 2, 3 s
