"""The PT100 smart sensor (examples/pt100_sensor.elab) run on the host board.

Expected values come from an independent Python model of what the docs
promise: the front end of docs/stdlib.md (1024 counts = 400.00 ohm,
Callendar-Van Dusen of IEC 60751 tabulated every 10 degC and interpolated
linearly, saturating outside the table), MovingAverage of 8 (fewer at
start), Linear calibration (C division, toward zero), Hysteresis (on above
alarm_high, off below alarm_high - 20), the channel `samples` with its 100
initial zeros feeding WindowStats over 100 tokens, and logical execution
time: a release at t latches the inputs, its outputs are published at
t + period.

docs/stdlib.md allows the linearisation to be off by one tenth where the
ADC step falls near a rounding boundary ("1304 or 1305"): the model gives
an interval [lo, hi] of acceptable tenths per count (a single value for
more than 80 % of the counts), and everything downstream carries that
interval.
"""

from __future__ import annotations

import math

import pytest

from native_testlib import DATA, Stimulus, Trace, cdiv, clamp, run

# Callendar-Van Dusen, IEC 60751.
R0, A, B, C = 100.0, 3.9083e-3, -5.775e-7, -4.183e-12


def cvd_ohm(t: float) -> float:
    r = R0 * (1.0 + A * t + B * t * t)
    if t < 0:
        r += R0 * C * (t - 100.0) * t ** 3
    return r


def cvd_inverse(r: float) -> float:
    """Exact inverse of the equation (bisection), for cross-checking the table."""
    lo, hi = -250.0, 900.0
    for _ in range(200):
        mid = (lo + hi) / 2
        if cvd_ohm(mid) < r:
            lo = mid
        else:
            hi = mid
    return (lo + hi) / 2


def table_degc(r: float, centiohm_table: bool = False) -> float:
    """Linear interpolation in the CVD table every 10 degC from -200 to 850,
    saturating outside it; the table exact or kept in 0.01 ohm."""
    points = [(t, cvd_ohm(t)) for t in range(-200, 851, 10)]
    if centiohm_table:
        points = [(t, round(ohm * 100) / 100) for t, ohm in points]
    if r <= points[0][1]:
        return -200.0
    if r >= points[-1][1]:
        return 850.0
    for (t0, r0), (t1, r1) in zip(points, points[1:]):
        if r0 <= r < r1:
            return t0 + 10.0 * (r - r0) / (r1 - r0)
    raise AssertionError(r)


def tenths_round(x: float) -> int:
    return math.floor(x + 0.5)


def linearize(counts: int) -> tuple[int, int]:
    """Acceptable outputs of Pt100Linearize, in 0.1 degC: the interpolated
    temperature of counts * 0.390625 ohm, rounded, with the resistance exact
    or resolved to 0.01 ohm, and the table exact or kept in 0.01 ohm (as
    pt100_linearize.c says it is); docs/stdlib.md's "1304 or 1305"."""
    r = counts * 400.0 / 1024.0
    values = [tenths_round(table_degc(rr, rounded) * 10)
              for rr in (r, math.floor(counts * 39.0625) / 100.0) for rounded in (False, True)]
    return min(values), max(values)


def exact(counts: int) -> int:
    lo, hi = linearize(counts)
    assert lo == hi, f"{counts} counts: {lo}..{hi} is not a single value"
    return lo


# ---------------------------------------------------------------------- the model's own checks


def test_reference_model_agrees_with_the_documented_examples():
    # docs/stdlib.md: 256 counts are 100.00 ohm, 0.0 degC; 384 counts are
    # 150.00 ohm, 130.45 degC (1304 or 1305).
    assert 256 * 400 / 1024 == 100.0 and 384 * 400 / 1024 == 150.0
    assert exact(256) == 0
    assert linearize(384) == (1304, 1305)
    assert abs(cvd_inverse(150.0) - 130.45) < 0.01
    # The table interpolation stays within 0.02 degC of the equation.
    for counts in range(48, 1000):
        r = counts * 400 / 1024
        assert abs(table_degc(r) - cvd_inverse(r)) < 0.02
    # Saturation below 18.52 ohm (-200 degC) and above 390.48 ohm (850 degC).
    assert exact(0) == exact(47) == -2000
    assert exact(1000) == exact(1023) == exact(65535) == 8500


# ---------------------------------------------------------------------- the chain


ACQUIRE_MS = 10


def simulate(stimulus: Stimulus, duration_ms: int):
    """Published values at each instant (every 10 ms) of [0, duration):
    {t_ms: {column: (lo, hi) or bool or None}}."""
    params0 = {"cal_gain": 1000, "cal_offset": 0, "alarm_high": 800}
    columns = stimulus.header
    window: list[int] = []
    alarm: bool | None = False
    stream: list[tuple[int, int]] = [(0, 0)] * 100  # channel `samples`, delay 100
    published = {"temperature": (0, 0), "alarm": False, "t_min": (0, 0), "t_max": (0, 0), "t_mean": (0, 0)}
    pending: dict[int, dict] = {}
    out = {}
    for t in range(0, duration_ms, ACQUIRE_MS):
        published.update(pending.pop(t, {}))
        out[t] = dict(published)
        p = {k: stimulus.param(k, t * 1000, ACQUIRE_MS * 1000, v) if k in columns else v for k, v in params0.items()}
        raw = stimulus.level("sensor.raw", t * 1000)
        window = (window + [raw])[-8:]
        avg = sum(window) // len(window)
        lo, hi = linearize(avg)
        cal = tuple(clamp(cdiv(x * p["cal_gain"], 1000) + p["cal_offset"], -32768, 32767) for x in (lo, hi))
        on, off = p["alarm_high"], p["alarm_high"] - 20
        if cal[0] > on:
            alarm = True
        elif cal[1] < off and cal[1] <= on:
            alarm = False
        elif not (cal[0] >= off and cal[1] <= on):
            alarm = None  # undecided: the interval straddles a threshold
        stream.append(cal)
        pending.setdefault(t + ACQUIRE_MS, {}).update(temperature=cal, alarm=alarm)
        if t % 1000 == 0:  # statistics released: 100 tokens
            m = t // 1000
            win = stream[100 * m:100 * m + 100]
            assert len(win) == 100
            pending.setdefault(t + 1000, {}).update(
                t_min=(min(w[0] for w in win), min(w[1] for w in win)),
                t_max=(max(w[0] for w in win), max(w[1] for w in win)),
                t_mean=(cdiv(sum(w[0] for w in win), 100), cdiv(sum(w[1] for w in win), 100)))
    return out


def check_against_model(trace: Trace, expected: dict) -> int:
    """Every instant, every output; returns how many checks were exact."""
    exact_checks = 0
    for t, values in expected.items():
        for column in ("temperature", "t_min", "t_max", "t_mean"):
            lo, hi = values[column]
            got = trace(column, t)
            assert lo <= got <= hi, f"{column} at {t} ms: {got}, expected {lo}" + (f"..{hi}" if hi != lo else "")
            exact_checks += lo == hi
        if values["alarm"] is not None:
            assert trace("alarm", t) == values["alarm"], f"alarm at {t} ms"
            assert trace("alarm_led.level", t) == values["alarm"], f"alarm_led.level at {t} ms"
    return exact_checks


@pytest.fixture(scope="module")
def chain(example_runs):
    """The example's run against data/pt100_sensor.stimulus.csv (5 s)."""
    return example_runs("pt100_sensor").trace, Stimulus(DATA / "pt100_sensor.stimulus.csv")


def test_chain_follows_the_model_at_every_instant(chain):
    trace, stim = chain
    expected = simulate(stim, 5000)
    checks = check_against_model(trace, expected)
    assert checks >= 0.75 * 4 * len(expected)  # most expectations are a single value
    # Nothing happens between instants: rows only at multiples of 10 ms.
    assert all(t % 10000 == 0 for t in trace.times)


def test_linearisation_of_known_counts(chain):
    """Settled values (8 samples after a step), worked out from the docs."""
    t = chain[0]
    assert t("temperature", 0) == 0 and t("temperature", 10) == 0   # 256 counts: 0.0 degC
    assert t("temperature", 280) == exact(330) == 748               # 128.91 ohm
    assert t("temperature", 480) == exact(400) == 1471              # 156.25 ohm
    assert t("temperature", 680) == exact(150) == -1041             # 58.59 ohm
    assert t("temperature", 880) == -2000                           # 0 counts: saturated
    assert t("temperature", 1080) == exact(48) == -1995             # just inside the table
    assert t("temperature", 1280) == exact(200) == -555
    assert t("temperature", 1480) == exact(600) == 3633
    assert t("temperature", 1680) == exact(900) == 7203
    assert t("temperature", 1880) == 8500                           # 390.63 ohm: saturated
    assert t("temperature", 2080) == 8500
    assert t("temperature", 2280) == 8500                           # far out of the ADC range
    assert t("temperature", 2480) == -2000                          # 47 counts: 18.36 ohm
    assert t("temperature", 2680) == exact(355) == 1004             # 138.67 ohm, about 100.4 degC
    assert t("temperature", 2880) in (1304, 1305)                   # docs/stdlib.md's example


def test_moving_average_and_let_delay(chain):
    """A step of the input shows one period after the release that reads it
    and takes 8 samples to settle."""
    t = chain[0]
    # raw 256 -> 330 at 200 ms: the release at 200 ms sees (7 * 256 + 330) / 8 = 265.
    assert t("temperature", 200) == 0
    assert t("temperature", 210) == exact(265)
    assert t("temperature", 220) == exact((6 * 256 + 2 * 330) // 8)
    assert t("temperature", 270) == exact((256 + 7 * 330) // 8)
    assert t("temperature", 280) == 748
    assert [time for time, _ in t.changes("temperature") if 200000 <= time <= 400000] == \
        [210000, 220000, 230000, 240000, 250000, 260000, 270000, 280000]


def test_calibration_params_latched_at_release(chain):
    t = chain[0]
    # cal_offset 52 written at 3200 ms: latched by the release at 3200 ms.
    assert t("cal_offset", 3190) == 0 and t("cal_offset", 3200) == 52
    assert t("temperature", 3200) == 748 and t("temperature", 3210) == 800
    # 53 written at 3403 ms: applies at the next instant, 3410 ms.
    assert t("cal_offset", 3400) == 52 and t("cal_offset", 3410) == 53
    assert t("temperature", 3410) == 800 and t("temperature", 3420) == 801
    # gain 1.1 and offset -5.0 from 4000 ms: 748 * 1100 / 1000 - 50 = 772.
    assert t("cal_gain", 4000) == 1100 and t("temperature", 4000) == 779
    assert t("temperature", 4010) == 772
    # Negative values divide toward zero: -1041 * 1.1 = -1145.1 -> -1145, - 50.
    assert t("temperature", 4280) == -1195
    # gain 2, offset +50.0 at the top of the table: 8500 * 2 + 500.
    assert t("temperature", 4880) == 17500


def test_alarm_hysteresis_at_exact_times(chain):
    t = chain[0]
    # 800 is not above alarm_high = 800; 801 is.
    assert (t("alarm", 3210), t("alarm", 3410)) == (0, 0)
    assert t("alarm", 3420) == 1 and t("alarm_led.level", 3420) == 1
    # 780 is not below 800 - 20 = 780; 779 is.
    assert t("temperature", 3610) == 780 and t("alarm", 3610) == 1
    assert t("temperature", 3810) == 779 and t("alarm", 3800) == 1 and t("alarm", 3810) == 0
    assert t("alarm_led.level", 3800) == 1 and t("alarm_led.level", 3810) == 0
    alarm = t.changes("alarm")
    assert (3420000, "1") in alarm and (3810000, "0") in alarm
    # alarm_high -150.0 degC from 4400 ms: -119.5 degC is above it at once.
    assert t("alarm", 4400) == 0 and t("alarm", 4410) == 1
    # The on and off times over the whole run, from the model.
    expected = simulate(chain[1], 5000)
    changes = [(ms * 1000, str(int(v["alarm"]))) for ms, v in sorted(expected.items())]
    model_changes = [c for i, c in enumerate(changes) if i == 0 or changes[i - 1][1] != c[1]]
    assert alarm == model_changes


def test_statistics_sees_100_samples_per_second(sanitized, tmp_path):
    """A ramp of one count per 10 ms: every window of 100 samples has
    distinct ends, so a window shifted by one sample would show."""
    stim = DATA / "pt100_stats.stimulus.csv"
    trace = run(sanitized["pt100_sensor"], tmp_path / "stats.csv", duration="4500ms", stimulus=stim).trace
    expected = simulate(Stimulus(stim), 4500)
    check_against_model(trace, expected)
    # By hand: the first window is the channel's 100 zeros, published at 1 s.
    for col in ("t_min", "t_max", "t_mean"):
        assert [c for c in trace.changes(col)][:1] == [(0, "0")]
        assert trace(col, 1990) == 0
        # The published statistics change at whole seconds only.
        assert all(time % 1_000_000 == 0 for time, _ in trace.changes(col))
    # Window 1 (published at 2 s): samples 0..99 of raw = 120 + 2k, whose
    # averages are 120 (first sample alone) .. mean(raw[92..99]) = 311.
    assert trace("t_min", 2000) in range(linearize(120)[0], linearize(120)[1] + 1)
    assert trace("t_max", 2000) in range(linearize(311)[0], linearize(311)[1] + 1)
    # Window 2 (at 3 s): samples 100..199, averages 313 .. 511.
    assert trace("t_min", 3000) in range(linearize(313)[0], linearize(313)[1] + 1)
    assert trace("t_max", 3000) in range(linearize(511)[0], linearize(511)[1] + 1)
    assert trace("t_min", 2990) == trace("t_min", 2000)
    # Window 1 crosses 0 degC: the mean is that of negative and positive samples.
    assert trace("t_min", 2000) < 0 < trace("t_max", 2000)
