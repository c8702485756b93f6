"""The PIC18 proxy (boards/pic18/pic18_remote.c) in the gpsim harness, its
link (the EUSART) on a pty, against `easylab remote`: the host-native
trace in lock-step for the models that fit the part (blink at 1 Mbaud),
in real time for
pt100_sensor at 115200 baud, a proxy of another device model refused with
the devices that differ, a model whose devices claim the EUSART refused,
and the proxy's program memory and RAM on the PIC18F4520."""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest

from easylab.board.registry import load_board
from easylab.board.resources import Resolved
from easylab.pipeline import lower_file
from easylab.remote.proxy import build_proxy
from remote_testlib import (EASYLAB, EXAMPLES, ROOT, SimulatedProxy, assert_host_trace_is_native, device_columns,
                            native_of, real_time_run, remote, run_native)

VARIANTS = ROOT / "boards" / "pic18" / "conformance"
BLINK = EXAMPLES / "blink.elab"
ENCODER_RATE = ROOT / "tests" / "pic18" / "models" / "encoder_rate.elab"


def pic18_proxy(build_cache, model: Path, mcu: str = "pic18f4520", baud: int = 115200):
    """The simulation build of ``model``'s PIC18 proxy (built once per session)."""
    def make(out: Path):
        program, result = lower_file(model)
        assert program is not None, result.report()
        return build_proxy(program, "pic18", out, mcu=mcu, sim=True, baud=baud)
    return build_cache.get(("pic18-proxy", str(model), mcu, baud), make)


def pic18_proxy_process(built, link: Path, *args: str) -> SimulatedProxy:
    """The proxy in the gpsim harness, the EUSART (uart0) on a pty."""
    assert "#define EL_PIC18_REMOTE_UART 0u" in (built.out_dir / "el_pic18_config.h").read_text()
    return SimulatedProxy(built.simulator, 0, link, *args)


def stimulus_of(model: Path) -> Path | None:
    for folder in (EXAMPLES, ROOT / "tests" / "pic18" / "data"):
        found = folder / f"{model.stem}.stimulus.csv"
        if found.exists():
            return found
    return None


# The models whose devices fit the part: the examples, and the board's
# variant of pneumatic_cylinder (the example's pins are the AVR's); one on
# the PIC18F4620; blink at 1 Mbaud (100 instruction cycles a byte); an
# encoder given 2,113 edges at up to 4 kHz, whose proxy must count each at
# its instant as the firmware does (tests/pic18/test_pic18_sim.py).
LOCK_STEP = [(BLINK, "pic18f4520", 1_000_000), (EXAMPLES / "cd_to_dat.elab", "pic18f4520", 115200),
             (EXAMPLES / "pt100_sensor.elab", "pic18f4520", 115200),
             (VARIANTS / "pneumatic_cylinder.elab", "pic18f4620", 115200),
             (ENCODER_RATE, "pic18f4520", 115200)]


@pytest.mark.parametrize("model,mcu,baud", LOCK_STEP, ids=[f"{m.stem}-{mcu}-{b}" for m, mcu, b in LOCK_STEP])
def test_the_pic18_proxy_in_lock_step_gives_the_native_trace(model, mcu, baud, build_cache, tmp_path):
    stimulus = stimulus_of(model)
    native = tmp_path / "native.csv"
    run_native(native_of(build_cache, model), native, "1s", stimulus)
    built = pic18_proxy(build_cache, model, mcu, baud)
    devices = device_columns(stimulus, model, tmp_path / "devices.csv") if stimulus else None
    proxy = pic18_proxy_process(built, tmp_path / "link", "--fast", *(["--stimulus", str(devices)] if devices else []))
    try:
        traced = tmp_path / "remote.csv"
        proc = remote(model, proxy.link, "--fast", "--baud", str(baud), "--duration", "1s", "--trace", str(traced),
                      *(["--stimulus", str(stimulus)] if stimulus else []))
        assert proc.returncode == 0, proc.stderr
    finally:
        err = proxy.end()
    assert traced.read_bytes() == native.read_bytes(), err


@pytest.mark.realtime
def test_the_pic18_proxy_in_real_time_gives_the_native_trace(build_cache, tmp_path):
    """pt100_sensor (10 ms deadlines) at 115200 baud, paced by the
    simulated MCU's clock."""
    model, stimulus = EXAMPLES / "pt100_sensor.elab", EXAMPLES / "pt100_sensor.stimulus.csv"
    native = tmp_path / "native.csv"
    run_native(native_of(build_cache, model), native, "1s", stimulus)
    built = pic18_proxy(build_cache, model)
    devices = device_columns(stimulus, model, tmp_path / "devices.csv")
    run = real_time_run(tmp_path, lambda d: pic18_proxy_process(built, d / "link", "--stimulus", str(devices)),
                        model, "--duration", "1s", "--stimulus", str(stimulus))
    proc, elapsed, err, traced = run.proc, run.elapsed, run.proxy_stderr, run.run_dir / "remote.csv"
    assert proc.returncode == 0, proc.stderr
    assert elapsed >= 1.0  # paced by the proxy's clock
    assert_host_trace_is_native(traced, native, proc, err)


def test_a_proxy_of_another_device_model_is_refused(build_cache, tmp_path):
    """blink's proxy against blink with its LED on another pin: refused,
    naming the device that differs, before any instant runs."""
    moved = tmp_path / "blink.elab"
    moved.write_text(BLINK.read_text().replace('pin = "PB5"', 'pin = "PB4"'))
    proxy = pic18_proxy_process(pic18_proxy(build_cache, BLINK), tmp_path / "link", "--fast")
    try:
        proc = remote(moved, proxy.link, "--fast", "--duration", "1s")
    finally:
        proxy.end()
    assert proc.returncode == 1
    assert re.search(r"the proxy runs another device model \(0x[0-9a-f]{8}, this model's is 0x[0-9a-f]{8}\): "
                     r"different: led; rebuild and flash the proxy \(easylab proxy\)", proc.stderr), proc.stderr


def test_easylab_proxy_builds_the_pic18_proxy(tmp_path):
    """Its program memory and RAM (deterministic, so a bound; RAM counts
    sdcc's 384-byte software stack), its link on the EUSART, its frame
    buffers and rings of blink's sizes."""
    proc = subprocess.run([*EASYLAB, "proxy", str(BLINK), "--board", "pic18", "-o", str(tmp_path / "p")],
                          capture_output=True, text=True, timeout=600, stdin=subprocess.DEVNULL)
    assert proc.returncode == 0, proc.stderr
    size = re.search(r"pic18f4520: program memory (\d+) of \d+ bytes .*RAM (\d+) of 1536 bytes", proc.stdout)
    flash, ram = int(size.group(1)), int(size.group(2))
    assert flash <= 19450 and ram <= 672, proc.stdout
    assert proc.stdout.splitlines()[-1] == str(tmp_path / "p" / "blink_proxy.hex")
    assert "#define EL_PIC18_REMOTE_UART 0u" in (tmp_path / "p" / "el_pic18_config.h").read_text()
    assert "#define EL_RMT_TX_FRAME 22u" in (tmp_path / "p" / "el_remote_config.h").read_text()


def test_a_model_whose_devices_claim_the_eusart_has_no_link(tmp_path):
    """No PIC18 driver takes a UART yet, so no model gets a device on the
    EUSART past the claims check; should one, the configuration the board
    generates stops a proxy build (only) with the reason."""
    from easylab.board.registry import board_module

    part = load_board("pic18").configure("pic18f4520").part
    lines = board_module("pic18", "devices").remote_link(part, Resolved(uarts={0: {"use": "device", "device": "cam"}}))
    header = tmp_path / "config.h"
    header.write_text("\n".join(lines) + "\n")
    assert subprocess.run(["gcc", "-E", str(header)], capture_output=True, text=True).returncode == 0
    proxy = subprocess.run(["gcc", "-E", "-DEL_REMOTE_PROXY=1", str(header)], capture_output=True, text=True)
    assert proxy.returncode != 0
    assert ("a remote-execution proxy needs a UART for its link: the pic18f4520's only UART is claimed "
            "(uart0 by cam); free it for the link") in proxy.stderr
