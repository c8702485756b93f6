"""The link between `easylab remote` and a proxy: frames and their CRC,
the device-model id, the two connect errors, corrupted frames, overruns."""

from __future__ import annotations

import os
import signal
import struct
import time

import pytest

from easylab.core.crc import crc16
from easylab.pipeline import lower_file
from easylab.remote import protocol as P
from easylab.remote.device_model import device_model
from easylab.remote.link import Link, NoAnswer, RemoteError
from easylab.remote.protocol import K
from easylab.remote.proxy import build_proxy
from remote_testlib import EXAMPLES, BaudMismatchRelay, Proxy, proxy_of, remote

BLINK = EXAMPLES / "blink.elab"
PT100 = EXAMPLES / "pt100_sensor.elab"


def until(condition, timeout: float = 10.0) -> None:
    deadline = time.monotonic() + timeout
    while not condition():
        assert time.monotonic() < deadline, "the condition did not come true in time"
        time.sleep(0.01)


def lower_text(tmp_path, text: str, name: str = "edited.elab"):
    path = tmp_path / name
    path.write_text(text)
    program, result = lower_file(path)
    assert program is not None, result.report()
    return path, program


def test_frames_carry_their_instant_and_a_crc():
    wire = P.encode(K.CMD_DOWN, 123456, b"\x00\x01\x02")
    assert wire.endswith(b"\x00") and b"\x00" not in wire[:-1]
    assert P.decode(wire[:-1]) == (K.CMD_DOWN, 123456, b"\x00\x01\x02")
    damaged = bytearray(wire[:-1])
    damaged[3] ^= 0x40 if damaged[3] != 0x40 else 0x01
    assert P.decode(bytes(damaged)) is None


def test_the_device_model_id_ignores_the_application(tmp_path):
    program, _ = lower_file(BLINK)
    text = BLINK.read_text()
    _, slower = lower_text(tmp_path, text.replace("= 500", "= 250").replace("SquareWave(half_period = half_period)",
                                                                           "SquareWave(half_period = half_period + 1)"))
    assert slower.program_id != program.program_id
    assert device_model(slower).id == device_model(program).id
    _, moved = lower_text(tmp_path, text.replace('"PB5"', '"PB4"'), "moved.elab")
    assert device_model(moved).id != device_model(program).id
    assert device_model(moved).device_ids != device_model(program).device_ids
    _, faster = lower_text(tmp_path, text.replace("period 1 ms", "period 2 ms"), "faster.elab")
    assert device_model(faster).id != device_model(program).id  # the instants of the writes moved
    assert device_model(faster).device_ids == device_model(program).device_ids


def test_a_declared_safe_value_and_the_fault_settings_change_the_device_model(tmp_path):
    """A safe value is part of the device model (the proxy applies it): a
    changed one changes the id, and the device's own id; so do K and the
    watchdog time. The safe value is also the datum's initial value."""
    program, _ = lower_file(BLINK)
    base = device_model(program)
    assert program.item("led.level").initial is False and base.overrun_limit == 3
    text = BLINK.read_text()
    _, safe = lower_text(tmp_path, text.replace('DigitalOut(pin = "PB5")', 'DigitalOut(pin = "PB5") safe level = true'),
                         "safe.elab")
    assert safe.item("led.level").initial is True
    assert device_model(safe).id != base.id and device_model(safe).device_ids != base.device_ids
    _, unsafe = lower_text(tmp_path, text.replace('DigitalOut(pin = "PB5")',
                                                  'DigitalOut(pin = "PB5") safe level = false'), "unsafe.elab")
    assert device_model(unsafe).id == base.id  # the default, declared
    _, k5 = lower_text(tmp_path, text + "remote overruns 5\n", "k5.elab")
    assert device_model(k5).overrun_limit == 5 and device_model(k5).id != base.id
    _, wd = lower_text(tmp_path, text + "remote watchdog 250 ms\n", "wd.elab")
    assert device_model(wd).watchdog_ticks == 250 and device_model(wd).id != base.id
    assert device_model(wd).device_ids == base.device_ids


def test_a_watchdog_time_shorter_than_the_frames_gap_is_refused(tmp_path):
    from easylab.core.errors import BuildError

    path, program = lower_text(tmp_path, BLINK.read_text().replace("period 1 ms", "period 20 ms")
                               + "remote watchdog 20 ms\n", "short.elab")
    with pytest.raises(BuildError) as err:
        build_proxy(program, "host", tmp_path / "proxy")
    line = path.read_text().splitlines().index("remote watchdog 20 ms") + 1
    assert str(err.value) == (f"{path}:{line}:17: the watchdog time (20 ms) must be longer than the longest time "
                              "between two frames of the device model (20 ms)")


def test_easylab_check_refuses_the_watchdog_times_easylab_proxy_refuses(tmp_path):
    """One rule (device_model.watchdog_problem) for both commands: blink's
    frames come every 1 ms, so 1 ms is refused at the time's line and
    column, 2 ms accepted by both."""
    import subprocess
    import sys

    def run(*argv: str) -> subprocess.CompletedProcess:
        return subprocess.run([sys.executable, "-m", "easylab", *argv], capture_output=True, text=True, timeout=300,
                              stdin=subprocess.DEVNULL)

    short = tmp_path / "short.elab"
    short.write_text(BLINK.read_text() + "remote watchdog 1 ms\n")
    line = short.read_text().splitlines().index("remote watchdog 1 ms") + 1
    rule = "the watchdog time (1 ms) must be longer than the longest time between two frames of the device model (1 ms)"
    checked = run("check", str(short))
    assert checked.returncode == 1, checked.stdout
    assert f"{short}:{line}:17: error: {rule}" in checked.stderr
    assert f"{short}: 1 error" in checked.stderr
    built = run("proxy", str(short), "-o", str(tmp_path / "p"))
    assert built.returncode == 1
    assert f"{short}:{line}:17: {rule}" in built.stderr
    longer = tmp_path / "longer.elab"
    longer.write_text(BLINK.read_text() + "remote watchdog 2 ms\n")
    assert run("check", str(longer)).returncode == 0
    assert run("proxy", str(longer), "-o", str(tmp_path / "q")).returncode == 0


def test_easylab_proxy_says_when_easylab_remote_will_refuse_its_baud_rate(tmp_path):
    """blink's 1 ms deadline does not fit 115200 baud: `easylab proxy` says
    so as an error with `easylab remote`'s own numbers (budget.refusal); the
    build stands for lock-step runs. At 1 Mbaud it fits: nothing said."""
    import subprocess
    import sys

    def run(*argv: str) -> subprocess.CompletedProcess:
        return subprocess.run([sys.executable, "-m", "easylab", *argv], capture_output=True, text=True, timeout=300,
                              stdin=subprocess.DEVNULL)

    slow = run("proxy", str(BLINK), "-o", str(tmp_path / "slow"), "--baud", "115200")
    assert slow.returncode == 0, slow.stderr
    refused = run("remote", str(BLINK), "--target", str(tmp_path / "nothing"), "--baud", "115200")
    assert refused.returncode == 1
    why = refused.stderr.strip().removeprefix("easylab remote: ")
    assert why.startswith("the link cannot carry the device data in time: main at tick 0: 24 bytes")
    assert (f"easylab proxy: warning: `easylab remote` will refuse a real-time run at 115200 baud: {why}; this proxy "
            "serves lock-step runs (easylab remote --fast) only") in slow.stderr
    fast = run("proxy", str(BLINK), "-o", str(tmp_path / "fast"), "--baud", "1000000")
    assert fast.returncode == 0 and fast.stderr == "", fast.stderr


def test_a_proxy_of_another_device_model_is_refused_by_name(build_cache, tmp_path):
    moved, _ = lower_text(tmp_path, BLINK.read_text().replace('"PB5"', '"PB4"'), "blink.elab")
    proxy = Proxy(proxy_of(build_cache, BLINK), tmp_path / "link", "--fast")
    try:
        proc = remote(moved, proxy.link, "--fast", "--duration", "10ms")
        assert proc.returncode == 1
        assert "runs another device model" in proc.stderr
        assert "different: led" in proc.stderr
        assert "rebuild and flash the proxy" in proc.stderr
        assert proxy.proc.poll() is None  # still waiting for a host of its own model
    finally:
        proxy.kill()


def test_nothing_answering_is_another_error(tmp_path):
    master, slave = os.openpty()
    try:
        started = time.monotonic()
        proc = remote(BLINK, os.ttyname(slave), "--fast", "--connect-timeout", "0.6")
        assert proc.returncode == 1
        assert "no proxy answers" in proc.stderr and "another device model" not in proc.stderr
        assert time.monotonic() - started < 30
        hellos = os.read(master, 4096)  # HELLO was repeated
        assert hellos.count(b"\x00") >= 2
    finally:
        os.close(master)
        os.close(slave)


def test_the_proxy_drops_a_corrupted_frame(build_cache, tmp_path):
    program, _ = lower_file(PT100)
    model = device_model(program)
    proxy = Proxy(proxy_of(build_cache, PT100), tmp_path / "link", "--fast")
    link = None
    try:
        link = Link(str(proxy.link), model)
        link.connect()
        link.start(lock_step=True)
        first = link.up(0, 5.0)
        assert first[0] == K.STATE_RUNNING and len(first) == 1 + model.frame_bytes(model.up_items([0]))
        # A DOWN for instant 0 whose CRC does not match: dropped, the proxy still waits.
        body = struct.pack("<BI", K.CMD_DOWN, 0) + struct.pack("<I", 1) + b"\x01"
        crc = crc16(body) ^ 0x0101
        link.transport.send(P.cobs_encode(body + bytes([crc & 0xFF, crc >> 8])) + b"\x00")
        link.down(0, 1, b"\x01")
        link.up(1, 5.0)  # the good frame let the proxy go on
        counters = link.counters()
        assert counters["bad_crc"] == 1
        assert counters["malformed"] == 0 and counters["overruns"] == 0
        link.stop()
        status, err = proxy.finish()
        assert status == 0, err
    finally:
        if link:
            link.close()
        proxy.kill()


def answer(link: Link, model, instants: int, value: bytes) -> None:
    """Answer the proxy's next ``instants`` UP frames of the single device
    task with its written data = ``value``."""
    for _ in range(instants):
        frame = link._receive(K.CMD_UP, 5.0)
        assert frame is not None, "no UP frame"
        link.down(frame[0], 1, value)


def trace_column(trace, name: str) -> list[tuple[int, str]]:
    rows = trace.read_text().splitlines()
    column = rows[0].split(",").index(name)
    return [(int(r.split(",")[0]), r.split(",")[column]) for r in rows[1:]]


SAFE_ALARM = 'DigitalOut(pin = "PB7") safe level = true'


@pytest.mark.parametrize("declared", [False, True], ids=["default", "declared"])
def test_overruns_in_a_row_apply_the_safe_values(declared, build_cache, tmp_path):
    """In real time, a DOWN that does not come by its deadline is an
    overrun (counted, the value stays); after K in a row the proxy applies
    the safe values, and a DOWN after its deadline is never applied. The
    safe value and K are the defaults (false, 3) or the model's (true, 5)."""
    if declared:
        path, program = lower_text(tmp_path, PT100.read_text().replace('DigitalOut(pin = "PB7")', SAFE_ALARM)
                                   + "remote overruns 5\n", "pt100_safe.elab")
        exe = build_proxy(program, "host", tmp_path / "proxy").executable
    else:
        program, _ = lower_file(PT100)
        exe = proxy_of(build_cache, PT100)
    safe, driven = ("1", b"\x00") if declared else ("0", b"\x01")
    model = device_model(program)
    assert model.overrun_limit == (5 if declared else 3)
    trace = tmp_path / "proxy.csv"
    proxy = Proxy(exe, tmp_path / "link", "--trace", str(trace))
    link = None
    try:
        link = Link(str(proxy.link), model)
        link.connect()
        link.start(lock_step=False)
        answer(link, model, 20, driven)  # alarm_led.level driven for 20 activations of `acquire` (10 ms)
        until(lambda: link.counters()["watchdog"] + link.counters()["overruns"] > 0)
        link.down(0, 1, driven)  # instant 0's value, long after its deadline
        until(lambda: link._request(K.CMD_COUNTERS)[0] == K.STATE_SAFE)
        counters = link.counters()
        assert counters["overruns"] >= model.overrun_limit
        assert counters["tasks"] == [counters["overruns"]]  # per proxy task: acquire, the one driving a device
        assert counters["watchdog"] == 0  # K overruns come first (10 ms deadlines, watchdog 100 ms)
        link.stop()
        status, err = proxy.finish()
        assert status == 0, err
        # One word: the proxy's own report names the overruns the COUNTERS
        # answer gives (`easylab remote` says the same), not its own lateness.
        assert f"overruns: acquire {counters['tasks'][0]} (the host's values came late" in err, err
    finally:
        if link:
            link.close()
        proxy.kill()
    values = trace_column(trace, "alarm_led.level")
    assert values[0][1] == safe  # the safe value from boot until the host's first value is due
    assert str(driven[0]) in {v for _, v in values}  # then the host's values, applied at their deadlines
    assert values[-1][1] == safe  # and the safe value again


@pytest.mark.parametrize("declared", [False, True], ids=["default", "declared"])
def test_the_watchdog_applies_the_safe_values_when_the_host_is_gone(declared, tmp_path):
    """A task with a 500 ms period: the watchdog (by default twice the
    longest gap between frames, 1 s; or the model's 1.5 s), measured from
    the instant stamped on the last frame (the one awaited when it came),
    fires before K overruns would. The safe value is false, or the model's
    true."""
    text = BLINK.read_text().replace("period 1 ms", "period 500 ms")
    if declared:
        text = text.replace('DigitalOut(pin = "PB5")', 'DigitalOut(pin = "PB5") safe level = true')
        text += "remote watchdog 1500 ms overruns 5\n"
    path, program = lower_text(tmp_path, text, "slow.elab")
    model = device_model(program)
    assert model.watchdog_ticks * model.tick_us == (1_500_000 if declared else 1_000_000)
    safe, driven = ("1", b"\x00") if declared else ("0", b"\x01")
    exe = build_proxy(program, "host", tmp_path / "proxy").executable
    trace = tmp_path / "proxy.csv"
    proxy = Proxy(exe, tmp_path / "link", "--trace", str(trace))
    link = None
    try:
        link = Link(str(proxy.link), model)
        link.connect()
        link.start(lock_step=False)
        answer(link, model, 1, driven)  # the led driven at 500 ms; then the host says nothing more
        # Silence is the stimulus here (any frame, even a question, feeds the
        # watchdog): the watchdog time and a margin pass before we ask.
        time.sleep(2.6 if declared else 1.8)
        counters = link.counters()
        assert link._request(K.CMD_COUNTERS)[0] == K.STATE_SAFE
        assert counters["watchdog"] == 1
        # the activations due at 1 s (and 1.5 s) overran, fewer than K
        assert counters["overruns"] == (2 if declared else 1) < model.overrun_limit
        link.stop()
        assert proxy.finish()[0] == 0
    finally:
        if link:
            link.close()
        proxy.kill()
    # The led is driven at the first deadline and back at its safe value at
    # the first instant one watchdog time after the instant stamped on the
    # last frame (it came while the proxy awaited instant 1, at 500 ms):
    # 1.5 s by default, 2 s (500 ms + 1.5 s) declared.
    back = 2_000_000 if declared else 1_500_000
    assert trace_column(trace, "led.level")[:3] == [(0, safe), (500000, str(driven[0])), (back, safe)]


def test_a_device_model_whose_frames_would_not_fit_is_refused(tmp_path):
    from easylab.core.errors import BuildError

    _, program = lower_text(tmp_path, """model wide
import std
device type Camera(ch: uint8) {
    claims adc[ch]
    out px: int16 rate 130
    driver "camera"
}
device cam: Camera(ch = 0)
var mean: int16
dataflow Look {
    stats = WindowStats<int16>(n = 130)
    cam.px -> stats.x
    stats.mean -> mean
}
task look period 10 ms { run Look }
""", "wide.elab")
    with pytest.raises(BuildError) as err:
        build_proxy(program, "host", tmp_path / "proxy")
    assert str(err.value) == ("wide: the device data of the tasks released at tick 0 (look) take 261 bytes in one "
                              f"frame, more than the link's {K.MAX_PAYLOAD}: release those tasks at different "
                              "instants, or read fewer data")


def test_random_frames_neither_crash_nor_confuse_the_proxy(tmp_path):
    """Thousands of frames with good CRCs and random commands, instants and
    payloads (every command but STOP), and random bytes, to a proxy built
    with ASan and UBSan: it answers HELLO afterwards, goes on in lock-step
    and ends cleanly on STOP."""
    import random


    program, _ = lower_file(PT100)
    model = device_model(program)
    exe = build_proxy(program, "host", tmp_path / "proxy",
                      extra_cflags=("-fsanitize=address,undefined", "-fno-sanitize-recover=all", "-g")).executable
    proxy = Proxy(exe, tmp_path / "link", "--fast")
    link = None
    rng = random.Random(15)
    try:
        link = Link(str(proxy.link), model)
        link.connect()
        link.start(lock_step=True)
        link.up(0, 5.0)
        commands = [c for c in range(256) if c != K.CMD_STOP]
        for batch in range(40):
            wire = bytearray()
            for _ in range(50):
                if rng.random() < 0.8:
                    payload = bytes(rng.randrange(256) for _ in range(rng.choice([0, 1, 4, 5, 8, 60, 243, 260])))
                    wire += P.encode(rng.choice(commands), rng.choice([0, 1, 2, rng.randrange(2 ** 32)]), payload)
                else:
                    wire += bytes(rng.randrange(256) for _ in range(rng.randrange(1, 40)))
            link.transport.send(bytes(wire) + b"\x00")
            link.transport.discard_input()  # the answers are not what this test reads
        link.transport.discard_input()
        link.connect()  # still answering (a random START may have put it in real time: that is allowed)
        counters = link.counters()
        assert counters["bad_crc"] + counters["malformed"] > 0
        link.stop()
        status, err = proxy.finish()
        assert status == 0, err
        assert "runtime error" not in err and "AddressSanitizer" not in err
    finally:
        if link:
            link.close()
        proxy.kill()


def test_easylab_proxy_builds_and_names_the_device_model(tmp_path):
    import subprocess
    import sys

    proc = subprocess.run([sys.executable, "-m", "easylab", "proxy", str(BLINK), "-o", str(tmp_path / "p")],
                          capture_output=True, text=True, timeout=300, stdin=subprocess.DEVNULL)
    assert proc.returncode == 0, proc.stderr
    program, _ = lower_file(BLINK)
    lines = proc.stdout.splitlines()
    assert f"device model 0x{device_model(program).id:08x}" in lines
    assert lines[-1] == str(tmp_path / "p" / "blink_proxy")
    wrong = subprocess.run([sys.executable, "-m", "easylab", "proxy", str(BLINK), "--board", "nosuch"],
                           capture_output=True, text=True, timeout=300, stdin=subprocess.DEVNULL)
    assert wrong.returncode == 1 and "unknown board 'nosuch'" in wrong.stderr
    not_a_proxy = subprocess.run([str(tmp_path / "p" / "blink_proxy"), "--help"], capture_output=True, text=True,
                                 timeout=30, stdin=subprocess.DEVNULL)
    assert "--link pty:LINK|tcp:PORT" in not_a_proxy.stdout
    bad_port = subprocess.run([str(tmp_path / "p" / "blink_proxy"), "--link", "tcp:99999"], capture_output=True,
                              text=True, timeout=30, stdin=subprocess.DEVNULL)
    assert bad_port.returncode == 2
    assert "--link tcp:99999: not a port number (0..65535)" in bad_port.stderr


def test_firmware_that_is_not_a_proxy_says_so(build_cache, tmp_path):
    import subprocess

    exe = build_cache.example("host", "blink").executable
    proc = subprocess.run([str(exe), "--fast", "--link", f"pty:{tmp_path / 'link'}"], capture_output=True, text=True,
                          timeout=60, stdin=subprocess.DEVNULL)
    assert proc.returncode == 2
    assert "--link: this program is not a remote-execution proxy (easylab proxy builds one)" in proc.stderr
    assert not (tmp_path / "link").exists()


def test_the_tcp_link_takes_one_host_at_a_time(build_cache, tmp_path):
    """On `--link tcp:PORT` a host that leaves does not end the proxy, and a
    new connection replaces the one before it."""
    program, _ = lower_file(BLINK)
    model = device_model(program)
    proxy = Proxy(proxy_of(build_cache, BLINK), tmp_path / "link", "--fast", tcp=True)
    links = []
    try:
        gone = Link(str(proxy.link), model)
        gone.connect()
        gone.close()  # a host that went away
        stale = Link(str(proxy.link), model)
        links.append(stale)
        stale.connect()
        current = Link(str(proxy.link), model)
        links.append(current)
        current.connect()  # replaces `stale`, whose connection the proxy closed
        with pytest.raises(RemoteError):
            stale.connect(0.6)
        assert proxy.proc.poll() is None
        current.start(lock_step=True)
        assert current.up(0, 5.0)[0] == K.STATE_RUNNING
        current.down(0, 1, b"\x01")
        assert current.up(1, 5.0)[0] == K.STATE_RUNNING
        current.stop()
        status, err = proxy.finish()
        assert status == 0, err
    finally:
        for link in links:
            link.close()
        proxy.kill()


# The proxy's frame sizes (header 5 and CRC 2 around each payload): the
# largest DOWN it receives; the largest of UP, the HELLO answer (7),
# COUNTERS (state, six link counters and one per proxy task: 1 + 2 * (6 + tasks)) and the DEVICE
# answer (5 and the longest device path).
FRAME_SIZES = {
    "blink": (5 + 4 + 1 + 2, 5 + 15 + 2),  # DOWN: mask, led.level; COUNTERS with one task
    "pt100_sensor": (5 + 4 + 1 + 2, 5 + 5 + len("sensor.adc") + 2),  # DOWN: mask, alarm_led.level; DEVICE sensor.adc
    "line_follower": (5 + 4 + 3 * 2 + 2, 5 + 5 + len("robot.drive.m1") + 2),  # three motor speeds; DEVICE
}


@pytest.mark.parametrize("name", FRAME_SIZES)
def test_the_proxy_buffers_hold_the_device_models_largest_frames(name):
    from easylab.board.registry import load_board
    from easylab.remote.proxy import render_proxy

    program, _ = lower_file(EXAMPLES / f"{name}.elab")
    sizes = device_model(program).frame_sizes()
    assert (sizes.rx, sizes.tx) == FRAME_SIZES[name]
    assert (sizes.rx_wire, sizes.tx_wire) == (sizes.rx + 2, sizes.tx + 2)  # COBS' first code byte, the delimiter
    config = render_proxy(program, load_board("host").configure(None))["el_remote_config.h"]
    assert f"#define EL_RMT_RX_FRAME {sizes.rx}u" in config and f"#define EL_RMT_TX_FRAME {sizes.tx}u" in config


def test_a_proxy_waiting_for_its_host_ends_at_the_first_sigterm(build_cache, tmp_path):
    """Waiting for START (no host yet) and waiting in lock-step for a DOWN
    that does not come, the first SIGTERM ends the proxy, with status 0,
    as it does between ticks."""
    exe = proxy_of(build_cache, BLINK)
    waiting = Proxy(exe, tmp_path / "boot-link")
    try:
        time.sleep(0.2)  # in its wait for START
        waiting.proc.send_signal(signal.SIGTERM)
        status, err = waiting.finish(timeout=5.0)  # before the fix: still waiting after the first SIGTERM
        assert status == 0, err
    finally:
        waiting.kill()

    program, _ = lower_file(BLINK)
    lock_step = Proxy(exe, tmp_path / "lock-step-link")
    link = None
    try:
        link = Link(str(lock_step.link), device_model(program))
        link.connect()
        link.start(lock_step=True)
        assert link.up(0, 5.0)[0] == K.STATE_RUNNING  # the proxy now waits for instant 0's DOWN
        lock_step.proc.send_signal(signal.SIGTERM)
        status, err = lock_step.finish(timeout=5.0)
        assert status == 0, err
    finally:
        if link:
            link.close()
        lock_step.kill()


def test_a_baud_rate_mismatch_is_named_with_its_fix(build_cache, tmp_path):
    """A proxy at 115200 baud and `easylab remote --baud 57600`, the two
    ends of a serial link on real ptys (BaudMismatchRelay resamples the
    bits of each way at the reader's rate): the host sees the proxy's
    bytes (a proxy answers damaged frames before START) but no valid frame,
    and says that they do not frame at its baud rate and to give both the
    same --baud. The same relay at equal rates carries a whole run."""
    exe = proxy_of(build_cache, PT100)
    for host_baud, expected in ((57600, 1), (115200, 0)):
        run_dir = tmp_path / str(host_baud)
        run_dir.mkdir()
        proxy = Proxy(exe, run_dir / "proxy-link", "--fast")
        relay = BaudMismatchRelay(run_dir / "proxy-link", run_dir / "link", 115200, host_baud)
        try:
            proc = remote(PT100, relay.link, "--fast", "--baud", str(host_baud), "--duration", "50ms",
                          "--connect-timeout", "2")
        finally:
            relay.close()
            proxy.kill()
        assert proc.returncode == expected, proc.stderr
        if expected:
            assert f"{relay.link}: the proxy's bytes do not frame at 57600 baud (" in proc.stderr
            assert ("the proxy runs at another baud rate, most likely; give `easylab proxy` and `easylab remote` "
                    "the same --baud") in proc.stderr
            assert "no proxy answers" not in proc.stderr
