"""The link budget's CPU term (docs/remote.md, "Link budget") on the PIC18,
against fresh measurements in gpsim (tools/proxy_cpu.py): the board's
coefficients bound the proxy's cycles per release instant of a wheel's
drive (encoder, PWM, three digital pins), whose 1 ms period
`easylab remote --board pic18` and `easylab proxy` refuse with the measured
numbers and whose suggested period they accept; and a proxy whose CPU
cannot keep its period still serves its link, over a real pty in the real
gpsim harness: its UP frames say it is behind its clock, COUNTERS and STOP
are answered, and `easylab remote` names the proxy's lateness."""

from __future__ import annotations

import re
import subprocess
import sys
import time
from pathlib import Path

import pytest

from easylab.board.registry import load_board
from easylab.pipeline import lower_file
from easylab.remote.budget import link_budget
from easylab.remote.device_model import device_model
from easylab.remote.link import Link
from easylab.remote.protocol import K
from easylab.remote.proxy import build_proxy
from remote_testlib import EASYLAB, ROOT, SimulatedProxy, remote

sys.path.insert(0, str(ROOT / "tools"))
import proxy_cpu  # noqa: E402  (tools/ is no package)

WHEEL = ROOT / "tests" / "remote" / "models" / "wheel_drive.elab"
MCU = "pic18f4520"
# The coefficients carry 5 % of headroom (tools/proxy_cpu.py, HEADROOM) and
# sum per-device differences: they may exceed a measurement by this much.
MARGIN = 1.15


def wheel_proxy(build_cache, baud: int):
    """The simulation build of the wheel drive's PIC18 proxy at ``baud``."""
    def make(out: Path):
        program, result = lower_file(WHEEL)
        assert program is not None, result.report()
        return build_proxy(program, "pic18", out, mcu=MCU, sim=True, baud=baud)
    return build_cache.get(("pic18-proxy", str(WHEEL), MCU, baud), make)


def measure_wheel(build_cache, work: Path, baud: int):
    """A fresh gpsim measurement of the wheel drive's proxy (30 and 90
    release instants in lock-step with the link at ``baud``)."""
    program, _ = lower_file(WHEEL)
    built = wheel_proxy(build_cache, baud)
    return proxy_cpu.measure_built(built.simulator, program, work, instants=30, baud=baud)


@pytest.fixture
def measured(build_cache, tmp_path):
    """The wheel drive's proxy measured at 1 Mbaud, the rate the refusals
    below are asked about."""
    return measure_wheel(build_cache, tmp_path / "measure", 1_000_000)


def measured_ms(m) -> float:
    """A measurement as the budget counts it: its cycles at 10 MIPS, the
    clock's interrupts taking their share."""
    return m.cycles_per_instant / (10e6 * (1 - m.tick_share)) * 1e3


@pytest.mark.parametrize("baud", [115200, 1_000_000])
def test_the_coefficients_bound_a_fresh_measurement(build_cache, tmp_path, baud):
    """At each rate the board has figures for, those figures bound the
    proxy's cycles measured at that rate."""
    program, _ = lower_file(WHEEL)
    board = load_board("pic18").configure(MCU)
    m = measure_wheel(build_cache, tmp_path / "measure", baud)
    (instant,) = link_budget(program, device_model(program), baud, board)
    assert measured_cycles_bound(m, instant.cpu.cycles), (instant.cpu.parts, m)
    assert m.tick_share <= instant.cpu.clock_share <= MARGIN * m.tick_share, m


def measured_cycles_bound(m, cycles: int) -> bool:
    """Do the budget's ``cycles`` bound measurement ``m``, not above MARGIN of it?"""
    return m.cycles_per_instant <= cycles <= MARGIN * m.cycles_per_instant


def test_the_figures_of_the_fastest_rate_not_above_the_links_count():
    """A link between two measured rates counts the slower rate's figures
    (more cycles: bytes come fewer per pass); one slower than every rate
    the slowest's."""
    program, _ = lower_file(WHEEL)
    board = load_board("pic18").configure(MCU)

    def cycles(baud: int) -> int:
        (instant,) = link_budget(program, device_model(program), baud, board)
        return instant.cpu.cycles

    assert cycles(9600) == cycles(115200) == cycles(500_000) > cycles(1_000_000) == cycles(2_000_000)


def test_the_wheel_drive_at_1_ms_is_refused_with_the_measured_numbers(measured, tmp_path):
    proc = remote(WHEEL, tmp_path / "no-link", "--board", "pic18", "--baud", "1000000")
    assert proc.returncode == 1, proc.stderr
    said = re.search(r"easylab remote: the proxy cannot keep up: control at tick 0: the PIC18F4520 proxy needs "
                     r"(\d+\.\d+) ms of CPU per instant \(instant (\d+\.\d+) ms, wheel \(encoder\) \d+\.\d+ ms, "
                     r"motor \(pwm_out\) \d+\.\d+ ms, forward \(digital_out\) \d+\.\d+ ms, brake \(digital_out\) "
                     r"\d+\.\d+ ms, limit \(digital_in\) \d+\.\d+ ms; its clock's interrupts \d+\.\d % of the CPU\) "
                     r"at 40 MHz; with its frames' 32 bytes on the wire \(0\.320 ms at 1000000 baud\) (\d+\.\d+) ms, "
                     r"but the deadline is 1 ms \(1 instant over; a period and deadline of at least (\d+) ms fit",
                     proc.stderr)
    assert said, proc.stderr
    cpu, total, period = float(said.group(1)), float(said.group(3)), int(said.group(4))
    now = measured_ms(measured)
    assert now <= cpu <= MARGIN * now, (cpu, measured)
    assert total == pytest.approx(cpu + 0.32, abs=0.011)
    # The measurement says the suggested period fits (the CPU and the wire
    # one after the other), and the budget takes it; a millisecond less not.
    assert now + 0.32 <= period
    for ms, refused in ((period, False), (period - 1, True)):
        model = tmp_path / f"wheel_drive_{ms}.elab"
        model.write_text(WHEEL.read_text().replace("period 1 ms", f"period {ms} ms"))
        proc = remote(model, tmp_path / "no-link", "--board", "pic18", "--baud", "1000000",
                      "--connect-timeout", "0.2")
        assert proc.returncode == 1
        assert ("the proxy cannot keep up" in proc.stderr) == refused, proc.stderr
        assert ("cannot open" in proc.stderr) != refused, proc.stderr
    # Without --board the proxy's CPU is not counted (a host-board proxy's is a PC's).
    proc = remote(WHEEL, tmp_path / "no-link", "--baud", "1000000", "--connect-timeout", "0.2")
    assert "cannot keep up" not in proc.stderr and "cannot open" in proc.stderr, proc.stderr


def test_easylab_proxy_warns_with_the_same_numbers(tmp_path):
    proc = subprocess.run([*EASYLAB, "proxy", str(WHEEL), "--board", "pic18", "--baud", "1000000", "-o",
                           str(tmp_path / "p")], capture_output=True, text=True, timeout=600,
                          stdin=subprocess.DEVNULL)
    assert proc.returncode == 0, proc.stderr
    refused = remote(WHEEL, tmp_path / "no-link", "--board", "pic18", "--baud", "1000000").stderr
    why = refused.split("easylab remote: ", 1)[1].strip()
    assert (f"easylab proxy: warning: `easylab remote --board pic18 --mcu {MCU}` will refuse a real-time run at "
            f"1000000 baud: {why}; this proxy serves lock-step runs (easylab remote --fast) only") in proc.stderr


def test_a_proxy_behind_its_clock_still_serves_its_link(build_cache, tmp_path):
    """The wheel drive's proxy at 1 ms in real time, its CPU some five
    times too slow: every instant runs late, yet the link is served at
    each. A scripted host answers 40 UP frames, nearly all saying the
    proxy is behind its clock; COUNTERS and STOP are answered; then
    `easylab remote` (without --board: no CPU budget) runs it and names the
    proxy's lateness, whether the run ends or the safe values end it."""
    program, _ = lower_file(WHEEL)
    model = device_model(program)
    built = wheel_proxy(build_cache, 1_000_000)
    proxy = SimulatedProxy(built.simulator, 0, tmp_path / "link")
    try:
        link = Link(str(proxy.link), model, 1_000_000)
        try:
            link.connect(10)
            link.start(lock_step=False)
            behind = 0
            for tick in range(40):
                up = link.up(tick, 10)
                behind += bool(up[0] & K.STATE_BEHIND)
                link.down(tick, 1, bytes(model.down_payload([0]) - K.DOWN_MASK))
            # The DOWN frames came late (each after the proxy's next instant
            # had begun), so its safe values hold by now; it still answers.
            time.sleep(0.05)  # the last DOWN taken: a request alone in the proxy's receive ring
            counters = link.counters()  # answered: NoAnswer otherwise
            link.stop()
        finally:
            link.close()
        assert behind >= 35, behind
        assert counters["frames"] >= 3 and counters["overruns"] >= 1, counters
        # After STOP the proxy restarted and waits for the next host.
        proc = remote(WHEEL, proxy.link, "--baud", "1000000", "--duration", "100ms")
    finally:
        err = proxy.end()
    assert re.search(r"the proxy was behind its clock at \d+ instants? \(instants processed after their time: its "
                     r"CPU cannot keep the device model's period; `easylab remote --board B` counts it in the link "
                     r"budget\)", proc.stderr), (proc.stderr, err)


def test_blink_through_the_avr_proxy_fits_at_1_mbaud_as_measured(tmp_path):
    """blink's 1 ms task through the ATmega328P's proxy, which the suite's
    real-time tests run at 1 Mbaud to the native trace: the budget with
    `--board avr` takes it, its figures for 1 Mbaud bound a fresh
    measurement in simavr (the median of three), and at 115200 baud (where the wire alone is too
    slow) it is refused."""
    blink = ROOT / "examples" / "blink.elab"
    program, _ = lower_file(blink)
    board = load_board("avr").configure("atmega328p")
    (instant,) = link_budget(program, device_model(program), 1_000_000, board)
    assert instant.fits, (instant.need_us, instant.cpu.parts)
    built = build_proxy(program, "avr", tmp_path / "proxy", mcu="atmega328p", sim=True, baud=1_000_000)
    m = proxy_cpu.median_measurement(
        lambda n: proxy_cpu.measure_built(built.simulator, program, tmp_path / f"measure{n}", instants=30, baud=1_000_000))
    assert measured_cycles_bound(m, instant.cpu.cycles), (instant.cpu.parts, m)
    assert instant.wire_us + m.cycles_per_instant / 16.0 < 1000
    proc = remote(blink, tmp_path / "no-link", "--board", "avr", "--mcu", "atmega328p", "--baud", "1000000",
                  "--connect-timeout", "0.2")
    assert "cannot keep up" not in proc.stderr and "cannot open" in proc.stderr, proc.stderr
    proc = remote(blink, tmp_path / "no-link", "--board", "avr", "--mcu", "atmega328p", "--baud", "115200")
    assert proc.returncode == 1 and "the proxy cannot keep up" in proc.stderr, proc.stderr
