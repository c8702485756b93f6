"""The AVR proxy (boards/avr/avr_remote.c) in the simavr harness, its link
UART on a pty, against `easylab remote`: the host-native trace in real
time at 115200 baud and at 1 Mbaud (simavr's UART times every byte by the
baud rate the firmware set), lock-step, the link budget's refusal, the
actuator pins at their safe values when the host dies, and the proxy's
flash and RAM on the ATmega328P."""

from __future__ import annotations

import re
import subprocess
import time
from pathlib import Path

import pytest

from easylab.pipeline import lower_file
from easylab.remote.device_model import device_model
from easylab.remote.host import COUNTERS_EVERY_US
from easylab.remote.link import Link
from easylab.remote.budget import refusal
from easylab.remote.protocol import K
from easylab.remote.proxy import build_proxy
from remote_testlib import (EASYLAB, EXAMPLES, LATE_HOST, REAL_TIME_ATTEMPTS, SimulatedProxy, device_columns, native_of,
                            assert_host_trace_is_native, real_time_run, remote, run_native)

BLINK = EXAMPLES / "blink.elab"
PT100 = EXAMPLES / "pt100_sensor.elab"


def avr_proxy(build_cache, model: Path, mcu: str, baud: int):
    """The simulation build of ``model``'s AVR proxy (built once per session)."""
    def make(out: Path):
        program, result = lower_file(model)
        assert program is not None, result.report()
        return build_proxy(program, "avr", out, mcu=mcu, sim=True, baud=baud)
    return build_cache.get(("avr-proxy", str(model), mcu, baud), make)


def link_uart(built) -> int:
    """The UART the build's configuration gives the proxy's link."""
    config = (built.out_dir / "el_avr_config.h").read_text()
    return int(re.search(r"#define EL_AVR_REMOTE_UART (\d+)u", config).group(1))


def avr_proxy_process(built, link: Path, *args: str) -> SimulatedProxy:
    """The proxy in the simavr harness (real time unless ``--fast`` is
    given), its link UART on a pty (symlink ``link``)."""
    return SimulatedProxy(built.simulator, link_uart(built), link, *args)


def changes(trace: Path, column: str, until_us: int) -> list[tuple[int, str]]:
    """(time, value) where a CSV trace's column takes a new value, before ``until_us``."""
    rows = trace.read_text().splitlines()
    at = rows[0].split(",").index(column)
    out: list[tuple[int, str]] = []
    for row in rows[1:]:
        cells = row.split(",")
        if int(cells[0]) < until_us and (not out or out[-1][1] != cells[at]):
            out.append((int(cells[0]), cells[at]))
    return out


# Every example at both baud rates, on the smallest part that has a UART
# for the link beside its devices' (line_follower's camera and
# pt100_sensor's Modbus take UARTs of their own).
MCU = {"blink": "atmega328p", "cd_to_dat": "atmega328p", "line_follower": "atmega2560",
       "pneumatic_cylinder": "atmega2560", "pt100_sensor": "atmega2560"}
REAL_TIME = [(name, mcu, baud) for name, mcu in MCU.items() for baud in (115200, 1_000_000)]




@pytest.mark.realtime
@pytest.mark.parametrize("name,mcu,baud", REAL_TIME)
def test_the_avr_proxy_in_real_time_gives_the_native_trace(name, mcu, baud, build_cache, tmp_path):
    """In real time the remote run's trace is the native one wherever the
    link budget fits; where it does not, the run is refused with the
    budget's numbers."""
    model, duration = EXAMPLES / f"{name}.elab", "1s"
    program, _ = lower_file(model)
    too_slow = refusal(program, device_model(program), baud)
    if too_slow is not None:
        refused = remote(model, tmp_path / "link", "--baud", str(baud), "--duration", duration)
        assert refused.returncode == 1 and too_slow in refused.stderr, refused.stderr
        return
    stimulus = EXAMPLES / f"{name}.stimulus.csv"
    stimulus = stimulus if stimulus.exists() else None
    given = ["--stimulus", str(stimulus)] if stimulus is not None else []
    native = tmp_path / "native.csv"
    run_native(native_of(build_cache, model), native, duration, stimulus)
    built = avr_proxy(build_cache, model, mcu, baud)
    devices = device_columns(stimulus, model, tmp_path / "devices.csv") if stimulus is not None else None
    inputs = ["--stimulus", str(devices)] if devices is not None else []
    run = real_time_run(tmp_path, lambda d: avr_proxy_process(built, d / "link", *inputs, "--trace", str(d / "proxy.csv")),
                        model, "--baud", str(baud), "--duration", duration, *given)
    proc, elapsed, err, run_dir = run.proc, run.elapsed, run.proxy_stderr, run.run_dir
    traced = run_dir / "remote.csv"
    assert proc.returncode == 0, proc.stderr
    if device_model(program).items:  # (a model without devices exchanges no frames: nothing paces it)
        assert elapsed >= 1.0  # paced by the proxy's clock
    assert_host_trace_is_native(traced, native, proc, err)
    # What the proxy read and applied (its own trace, from the MCU's RAM) is
    # the firmware's too, unless the host's values came late.
    if "overruns" not in proc.stderr:
        for item in device_model(program).items:
            assert changes(run_dir / "proxy.csv", item.name, 1_000_000) == changes(native, item.name, 1_000_000)


def blink_at_1_khz_over_tcp(build_cache, tmp_path, sim_prefix: list[str], *args: str, duration: str = "3s",
                            most_late: int | None = None) -> None:
    """blink's 1 ms task for ``duration`` through the AVR proxy at 1 Mbaud in real
    time, the harness's link UART on TCP (started under ``sim_prefix``),
    `easylab remote ARGS`: its trace is the native one (a few late values
    held, never K in a row, and at most ``most_late`` in all if given).
    Tried again at most REAL_TIME_ATTEMPTS times when K came in a row or
    more than ``most_late``."""
    import socket

    stimulus = EXAMPLES / "blink.stimulus.csv"
    native = tmp_path / "native.csv"
    run_native(native_of(build_cache, BLINK), native, duration, stimulus)
    built = avr_proxy(build_cache, BLINK, "atmega328p", 1_000_000)
    missed = []
    for attempt in range(REAL_TIME_ATTEMPTS):
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            port = s.getsockname()[1]
        sim = subprocess.Popen([*sim_prefix, str(built.simulator), f"--uart{link_uart(built)}", f"tcp:{port}"],
                               stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, stdin=subprocess.DEVNULL)
        try:
            time.sleep(0.5)  # the harness listens
            traced = tmp_path / f"remote{attempt}.csv"
            proc = remote(BLINK, f"socket://127.0.0.1:{port}", "--baud", "1000000", "--duration", duration,
                          "--stimulus", str(stimulus), "--trace", str(traced), *args)
        finally:
            sim.terminate()
            sim.communicate(timeout=30)
        if proc.returncode != 0:
            assert LATE_HOST in proc.stderr, proc.stderr
            missed.append(proc.stderr.strip())
            continue
        assert "warning" not in proc.stderr, proc.stderr
        assert_host_trace_is_native(traced, native, proc)
        counted = re.search(r"the proxy counted (\d+) overruns", proc.stderr)
        if most_late is not None and counted and int(counted.group(1)) > most_late:
            missed.append(proc.stderr.strip())
            continue
        return
    pytest.fail(f"K late values in a row, or more than {most_late} late, in every one of {REAL_TIME_ATTEMPTS} "
                "runs:\n" + "\n".join(missed))


@pytest.mark.realtime
def test_blink_at_1_khz_on_an_idle_machine(build_cache, tmp_path):
    """Nothing beside it, ordinary scheduling, no option: at blink's 1 ms
    deadline `easylab remote` polls its link instead of sleeping until a
    frame comes (a sleeping process on an idle machine was woken up to
    milliseconds late: three late values in a row within seconds), and the
    10 s run at 1 Mbaud gives the native trace with at most 5 late values
    (polling: 1 in 90,000 instants here; `--wait sleep`: 12 to 13 in each
    run of 10,000 that did not end in the safe state, docs/benchmarks.md)."""
    blink_at_1_khz_over_tcp(build_cache, tmp_path, [], duration="10s", most_late=5)


@pytest.mark.realtime
def test_blink_at_1_khz_beside_busy_processes_with_realtime_over_tcp(build_cache, tmp_path):
    """Two busy processes beside it: `easylab remote --realtime` (SCHED_FIFO)
    over a TCP link to the harness (itself under `chrt -f`) keeps blink's
    1 kHz run going, and its trace is the native one."""
    import realtime_peers

    prefix = realtime_peers.real_time_prefix()
    if not prefix:
        pytest.skip("this system does not allow real-time scheduling (chrt -f)")
    hogs = [subprocess.Popen(["nice", "-n", "19", "sh", "-c", "while :; do :; done"]) for _ in range(2)]
    try:
        blink_at_1_khz_over_tcp(build_cache, tmp_path, prefix, "--realtime")
    finally:
        for hog in hogs:
            hog.kill()
            hog.wait()


def test_lock_step_and_the_budget_at_each_baud_rate(build_cache, tmp_path):
    """blink (a 1 ms deadline) is refused at 115200 baud with the budget's
    numbers; at 1 Mbaud it fits, and in lock-step the trace is the
    firmware's."""
    refused = remote(BLINK, tmp_path / "link", "--baud", "115200", "--duration", "1s")
    assert refused.returncode == 1
    assert ("the link cannot carry the device data in time: main at tick 0: 24 bytes per instant (UP 10, DOWN 14) "
            "take 2.083 ms at 115200 baud; the deadline is 1 ms") in refused.stderr
    stimulus = EXAMPLES / "blink.stimulus.csv"
    native = tmp_path / "native.csv"
    run_native(native_of(build_cache, BLINK), native, "1s", stimulus)
    proxy = avr_proxy_process(avr_proxy(build_cache, BLINK, "atmega328p", 1_000_000), tmp_path / "link", "--fast")
    try:
        traced = tmp_path / "remote.csv"
        proc = remote(BLINK, proxy.link, "--baud", "1000000", "--fast", "--duration", "1s", "--trace", str(traced),
                      "--stimulus", str(stimulus))
        assert proc.returncode == 0, proc.stderr
    finally:
        err = proxy.end()
    assert traced.read_bytes() == native.read_bytes(), err


# Link loss: (model text, MCU, the host's params keeping the actuator on,
# the actuator datum and its pin, what applies the safe values). acquire's
# 10 ms deadlines: K overruns in a row (40 ms) before the watchdog (100 ms);
# a 500 ms task: the watchdog (1 s, stamped with the instant awaited when
# the last frame came) before K overruns (1.5 s).
LINK_LOSS = {
    "overruns": (None, "atmega2560", "alarm_high\n0,-2000", "alarm_led.level", "PB7"),  # pt100_sensor itself
    "watchdog": (BLINK.read_text().replace("period 1 ms", "period 500 ms"), "atmega328p", "half_period\n0,5000",
                 "led.level", "PB5"),
}


def downs_among(frames: int, period_us: int) -> int:
    """The DOWN frames among ``frames`` a real-time host sent: after the
    DOWN of instant 0, and then after a DOWN at least COUNTERS_EVERY_US of
    logical time later, it asks for the counters (docs/remote.md,
    "Timing"); a host killed between a DOWN and its request sent one less."""
    every = max(1, -(-COUNTERS_EVERY_US // period_us))  # DOWN frames per request
    return next(d for d in range(frames + 1) if d + -(-d // every) >= frames)


@pytest.mark.realtime
@pytest.mark.parametrize("case", LINK_LOSS)
def test_the_actuators_reach_their_safe_values_when_the_host_dies(case, build_cache, tmp_path):
    """The host is killed mid-run: the actuator (the host keeps it on) is
    back at its safe value within the watchdog time of the last frame, on
    the pin (the harness's pin trace) and in the proxy's RAM."""
    text, mcu, params, datum, pin = LINK_LOSS[case]
    model = PT100 if text is None else tmp_path / "model.elab"
    if text is not None:
        model.write_text(text)
    program, _ = lower_file(model)
    dm = device_model(program)
    built = avr_proxy(build_cache, model, mcu, 115200)
    host_stimulus = tmp_path / "params.csv"
    host_stimulus.write_text(f"time_us,{params}\n")
    devices = device_columns(EXAMPLES / "pt100_sensor.stimulus.csv", model, tmp_path / "devices.csv") \
        if case == "overruns" else None  # the sensor's readings (blink reads no device)
    period_us = program.tasks[dm.tasks[0].task].period * dm.tick_us
    watchdog_us = dm.watchdog_ticks * dm.tick_us
    late = []
    for attempt in range(REAL_TIME_ATTEMPTS):
        run_dir = tmp_path / f"run{attempt}"
        run_dir.mkdir()
        pins, trace = run_dir / "pins.csv", run_dir / "proxy.csv"
        proxy = avr_proxy_process(built, run_dir / "link", "--pins", str(pins), "--trace", str(trace),
                         *(["--stimulus", str(devices)] if devices else []))
        try:
            link = Link(str(proxy.link), dm)
            link.connect()  # one HELLO: the proxy is up before the host comes
            link.close()
            host = subprocess.Popen([*EASYLAB, "remote", str(model), "--target", str(proxy.link), "--stimulus",
                                     str(host_stimulus)], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                                    text=True, stdin=subprocess.DEVNULL)
            time.sleep(3.0)  # start-up, then the host runs for a while
            if host.poll() is not None:
                err = host.communicate()[1]
                assert LATE_HOST in err, err  # the only way the host may end by itself here
                late.append(err.strip())
                continue
            host.kill()
            host.communicate()
            time.sleep((watchdog_us + period_us) / 1e6 + 0.5)
            link = Link(str(proxy.link), dm)
            link.connect()
            counters = link.counters()
            assert link._request(K.CMD_COUNTERS)[0] == K.STATE_SAFE
            link.close()
        finally:
            proxy.end()
        break
    else:
        pytest.fail(f"the host was late in every one of {REAL_TIME_ATTEMPTS} runs:\n" + "\n".join(late))
    if case == "overruns":
        assert counters["overruns"] >= dm.overrun_limit and counters["watchdog"] == 0
    else:
        assert counters["watchdog"] == 1 and counters["overruns"] < dm.overrun_limit
    # Valid frames: our HELLO, the host's HELLO and START, its DOWN frames
    # (one per activation, from instant 0) with its COUNTERS requests, our
    # second HELLO and COUNTERS.
    downs = downs_among(counters["frames"] - 5, period_us)
    assert downs >= 2
    last_frame_us = (downs - 1) * period_us  # the instant of the last DOWN (it came by that activation's deadline)
    level = changes(trace, datum, 10**12)
    assert [v for _, v in level] == ["0", "1", "0"]  # safe at boot, the host's value, safe again
    on_us, off_us = level[1][0], level[2][0]
    assert 0 < off_us - last_frame_us <= watchdog_us + period_us
    # The pin follows at the same instants (the pin trace counts from the MCU's reset, not from START).
    rows = [r.split(",") for r in pins.read_text().splitlines()[1:] if r.split(",")[2] == pin]
    assert [r[3] for r in rows] == ["0", "1", "0"]
    pin_on, pin_off = int(rows[1][1]), int(rows[2][1])
    assert abs((pin_off - pin_on) - (off_us - on_us)) <= dm.tick_us


def test_easylab_proxy_builds_the_avr_proxy_for_the_atmega328p(tmp_path):
    """Its flash and RAM (deterministic, so a bound), its link on uart0, its
    ticks 32-bit although blink's timing allows 16 (the link's watchdog
    counts in 32: runtime_c/el_types.h)."""
    proc = subprocess.run([*EASYLAB, "proxy", str(BLINK), "--board", "avr", "--mcu", "atmega328p", "-o",
                           str(tmp_path / "p")], capture_output=True, text=True, timeout=300, stdin=subprocess.DEVNULL)
    assert proc.returncode == 0, proc.stderr
    size = re.search(r"atmega328p: flash (\d+) of \d+ bytes .*RAM (\d+) of 2048 bytes", proc.stdout)
    flash, ram = int(size.group(1)), int(size.group(2))
    assert flash <= 4864 and ram <= 288, proc.stdout
    assert proc.stdout.splitlines()[-1] == str(tmp_path / "p" / "blink_proxy.elf")
    assert "#define EL_AVR_REMOTE_UART 0u" in (tmp_path / "p" / "el_avr_config.h").read_text()
    # flashed as firmware is: through the bootloader, the proxy's image
    hex_file = tmp_path / "p" / "blink_proxy.hex"
    assert f"flash: avrdude -p m328p -c arduino -P PORT -b 115200 -D -U flash:w:{hex_file}:i" in proc.stdout
    flash = subprocess.run([*EASYLAB, "flash", str(BLINK), "--board", "avr", "--mcu", "atmega328p", "--proxy", "-o",
                            str(tmp_path / "p"), "--port", "/dev/ttyACM0", "--print"], capture_output=True, text=True,
                           timeout=300, stdin=subprocess.DEVNULL)
    assert flash.returncode == 0, flash.stderr
    assert flash.stdout.strip() == f"avrdude -p m328p -c arduino -P /dev/ttyACM0 -b 115200 -D -U flash:w:{hex_file}:i"
    missing = subprocess.run([*EASYLAB, "flash", str(BLINK), "--board", "avr", "--proxy", "-o", str(tmp_path / "q"),
                              "--port", "/dev/ttyACM0"], capture_output=True, text=True, timeout=300,
                             stdin=subprocess.DEVNULL)
    assert missing.returncode != 0 and f"nothing built in {tmp_path / 'q'} to flash: build it first (easylab proxy" \
        in missing.stderr
    nm = subprocess.run(["avr-nm", "-S", str(tmp_path / "p" / "blink_proxy.elf")], capture_output=True, text=True,
                        check=True).stdout
    assert any(line.split()[1:] == ["00000004", "b", "el_now"] for line in nm.splitlines()), nm


def test_a_part_whose_every_uart_a_device_claims_has_no_link(tmp_path):
    from easylab.core.errors import BuildError

    model = tmp_path / "camera.elab"
    model.write_text(EXAMPLES.joinpath("blink.elab").read_text().replace(
        'device led: DigitalOut(pin = "PB5")', 'device led: DigitalOut(pin = "PB5")\n'
        'device type Cam() {\n    claims uart[0]\n    out line: int16\n    driver "line_camera"\n}\n'
        'device cam: Cam()').replace("debug on uart0 baud 115200", ""))
    program, result = lower_file(model)
    assert program is not None, result.report()
    with pytest.raises(BuildError) as err:
        build_proxy(program, "avr", tmp_path / "p", mcu="atmega328p")
    assert ("a remote-execution proxy needs a UART for its link: every UART of the atmega328p is claimed "
            "(uart0 by cam); build for another --mcu") in str(err.value)
