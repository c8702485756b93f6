"""Charts on the host board: the pneumatic cylinder's sequence (timeout
fault included) and the line follower's parallel branches.

Chart semantics (docs/ir.md, "charts"): the first activation enters the
initial step; later activations add the task period to Step.time, choose
transitions on the values latched at release, fire them, then run the
actions of the active steps. Everything, the step activity included, is
published at the task's deadline (the end of its period here), so a
transition taken by the release at t shows at t + period. The expected
timelines below are worked out by hand from the stimulus files.
"""

from __future__ import annotations

import pytest

from native_testlib import DATA, Stimulus, cdiv, clamp


def steps_at(timeline: list[tuple[int, str]], t_ms: int) -> str:
    """The published activity at t_ms according to a list of changes."""
    value = ""
    for at, steps in timeline:
        if at <= t_ms:
            value = steps
    return value


def pid(state: dict, setpoint: int, measured: int, kp: int, ki: int, kd: int, lo: int, hi: int) -> int:
    """std's PID: gains in 1/1000, C division, the integral held while the
    output saturates in the error's direction (docs/stdlib.md)."""
    error = setpoint - measured
    candidate = clamp(state["integral"] + error * ki, -2 ** 31, 2 ** 31 - 1)
    out = cdiv(error * kp + candidate + (error - state["prev"]) * kd, 1000)
    if out > hi:
        out = hi
        if error < 0:
            state["integral"] = candidate
    elif out < lo:
        out = lo
        if error > 0:
            state["integral"] = candidate
    else:
        state["integral"] = candidate
    state["prev"] = error
    return out


# ====================================================================== pneumatic cylinder

# data/pneumatic_cylinder.stimulus.csv, control task every 5 ms:
#   100 start_cmd -> Extending (shows at 105); 300 end_out -> Extended (305,
#   cycles 1); 500 start_cmd off -> Retracting (505); 600 end_in -> Retracted
#   (605); 800 start_cmd -> Extending (805); no end switch: Extending.time is
#   2000 at the release at 2800 and 2005 > timeout at 2805 -> Fault (2810);
#   3100 reset_cmd -> Retracting (3105); 3200 timeout := 100 ms and reset off:
#   Retracting.time is 100 at 3200, 105 at 3205 -> Fault (3210); 3300 reset
#   and end_in: Fault -> Retracting (3305), then end_in at the next release
#   -> Retracted (3310); 3400 start_cmd, position 950 >= target 900:
#   Extending (3405), Extended at the next release (3410, cycles 2).
CYLINDER = [(0, ""), (5, "Retracted"), (105, "Extending"), (305, "Extended"), (505, "Retracting"),
            (605, "Retracted"), (805, "Extending"), (2810, "Fault"), (3105, "Retracting"), (3210, "Fault"),
            (3305, "Retracting"), (3310, "Retracted"), (3405, "Extending"), (3410, "Extended")]


@pytest.fixture(scope="module")
def cylinder(example_runs):
    return example_runs("pneumatic_cylinder").trace


def test_cylinder_steps_at_exact_times(cylinder):
    assert cylinder.changes("Cylinder.active") == [(ms * 1000, steps) for ms, steps in CYLINDER]


def test_cylinder_timeout_fault(cylinder):
    t = cylinder
    # Extending entered by the release at 800 ms: still there after 2000 ms
    # (not > timeout), Fault once 2005 ms have passed.
    assert t("Cylinder.active", 2805) == "Extending"
    assert t("Cylinder.active", 2810) == "Fault"
    assert t("alarm", 2805) == 0 and t("alarm", 2810) == 1
    # The lamp task (100 ms) latches alarm at 2900 and publishes at 3000.
    assert t("fault_lamp.level", 2990) == 0 and t("fault_lamp.level", 3000) == 1
    # A 100 ms timeout written at 3200 ms: Retracting (entered at 3100) faults at 3210.
    assert t("timeout", 3195) == 2000 and t("timeout", 3200) == 100
    assert t("Cylinder.active", 3205) == "Retracting" and t("Cylinder.active", 3210) == "Fault"
    # Retracted's entry action clears the alarm; the lamp follows one lamp period later.
    assert t("alarm", 3305) == 1 and t("alarm", 3310) == 0
    assert t("fault_lamp.level", 3490) == 1 and t("fault_lamp.level", 3500) == 0
    assert t.changes("alarm") == [(0, "0"), (2810000, "1"), (3310000, "0")]
    assert t.changes("fault_lamp.level") == [(0, "0"), (3000000, "1"), (3500000, "0")]


def test_cylinder_entry_actions_and_position_guard(cylinder):
    t = cylinder
    assert t.changes("cycles") == [(0, "0"), (305000, "1"), (3410000, "2")]
    # position 950 >= target 900 ends Extending without an end switch.
    assert t("end_out.level", 3405) == 0 and t("Cylinder.active", 3410) == "Extended"


def test_cylinder_valve_follows_the_steps(cylinder):
    """PositionControl runs while Extending or Extended (the PID keeps its
    state between them), Vent (duty 0) in the other steps."""
    t = cylinder
    stim = Stimulus(DATA / "pneumatic_cylinder.stimulus.csv")
    # By hand: at 105 ms the PID sees error 900: 900*400/1000 + 900*20/1000
    # = 378 > 255, saturated (and the integral stays 0); at 205 ms error
    # 450: (180000 + 9000) / 1000 = 189, then +9 per release.
    assert t("valve.duty", 105) == 255 and t("drive", 105) == 255
    assert [t("drive", ms) for ms in (205, 210, 215)] == [189, 198, 207]
    assert t("valve.duty", 505) == 0 and t("drive", 505) == t("drive", 500)
    state = {"integral": 0, "prev": 0}
    drive = 0
    for release in range(0, 3600 - 5, 5):
        step = steps_at(CYLINDER, release + 5)  # the step whose actions ran
        if step in ("Extending", "Extended"):
            drive = pid(state, 900, stim.level("position.value", release * 1000), 400, 20, 0, 0, 255)
            duty = drive
        else:
            duty = 0
        assert t("drive", release + 5) == drive, f"drive at {release + 5} ms"
        assert t("valve.duty", release + 5) == duty, f"valve.duty at {release + 5} ms"


# ====================================================================== line follower

# data/line_follower.stimulus.csv, control task every 10 ms: go at 100 ->
# Drive+Monitor at 110; left sensor 700 > stop_dist at 300: Watch (run by
# Monitor) sees it at 300, obstacle published at 310, both branches leave at
# 310 (DriveDone+MonitorDone at 320), converge at 320 (Idle at 330); the
# obstacle clears at 500 (Watch in Idle, published 510), the divergence
# fires at 510 (520); bumper at 600 (620, Idle 630), released at 700 (720);
# go off at 800 (810, Idle 820); go at 850 with the front sensor at 600
# (not > 600): 860; 601 at 900: obstacle at 910, 920, Idle at 930.
MISSION = [(0, ""), (10, "Idle"), (110, "Drive+Monitor"), (320, "DriveDone+MonitorDone"), (330, "Idle"),
           (520, "Drive+Monitor"), (620, "DriveDone+MonitorDone"), (630, "Idle"), (720, "Drive+Monitor"),
           (810, "DriveDone+MonitorDone"), (820, "Idle"), (860, "Drive+Monitor"),
           (920, "DriveDone+MonitorDone"), (930, "Idle")]


@pytest.fixture(scope="module")
def follower(example_runs):
    return example_runs("line_follower").trace


def test_mission_branches_diverge_and_converge(follower):
    assert follower.changes("Mission.active") == [(ms * 1000, steps) for ms, steps in MISSION]
    assert follower.changes("obstacle") == [(0, "0"), (310000, "1"), (510000, "0"), (610000, "1"),
                                            (710000, "0"), (910000, "1")]
    # Idle does not leave while the obstacle is there, go or not.
    assert all(follower("Mission.active", ms) == "Idle" for ms in range(330, 520, 10))


def vision(stim: Stimulus, duration_ms: int) -> dict[int, int]:
    """line published at each 10 ms instant: LowPass<int16>(alpha = 300) of
    the camera offset, one release every 50 ms."""
    acc, line, out, pending = 0, 0, {}, {}
    for t in range(0, duration_ms, 10):
        line = pending.pop(t, line)
        out[t] = line
        if t % 50 == 0:
            x = stim.level("robot.camera.offset", t * 1000)
            acc = clamp(acc + cdiv((x - acc) * 300, 1000), -32768, 32767)
            pending[t + 50] = acc
    return out


def test_motor_speeds_while_driving_and_halted(follower):
    t = follower
    stim = Stimulus(DATA / "line_follower.stimulus.csv")
    line = vision(stim, 1000)
    # By hand: camera 50 from 0 ms: line 15 at 50 ms, 25 at 100 ms. The
    # release at 100 ms drives with omega = -25 * 800 / 1000 = -20:
    # w1 = w2 = -20 - 120 / 2 = -80, w3 = -20 + 120 = 100.
    assert (line[50], line[100]) == (15, 25) and (t("line", 50), t("line", 100)) == (15, 25)
    assert [t(f"robot.drive.m{i}.speed", 110) for i in (1, 2, 3)] == [-80, -80, 100]
    # Camera -80 from 600 ms: 47 + (-127 * 300) / 1000 = 47 - 38 (toward zero) = 9.
    assert t("line", 650) == 9 and t("line", 700) == -17
    # The release at 710 ms drives on line -17: omega = 13 (toward zero).
    assert [t(f"robot.drive.m{i}.speed", 720) for i in (1, 2, 3)] == [-47, -47, 133]
    # Halted in Idle and in DriveDone.
    for ms in (10, 100, 320, 330, 510, 620, 810, 990):
        assert [t(f"robot.drive.m{i}.speed", ms) for i in (1, 2, 3)] == [0, 0, 0], ms
    for ms in range(0, 1000, 10):
        assert t("line", ms) == line[ms], f"line at {ms} ms"
        if ms == 0:
            continue
        drive_branch = steps_at(MISSION, ms).split("+")[0]
        if drive_branch == "Drive":  # FollowLine ran at ms - 10 on the line latched then
            omega = clamp(cdiv(-line[ms - 10] * 800, 1000), -255, 255)
            expected = [omega - 60, omega - 60, omega + 120]
        else:  # Idle or DriveDone: Halt
            expected = [0, 0, 0]
        assert [t(f"robot.drive.m{i}.speed", ms) for i in (1, 2, 3)] == expected, f"speeds at {ms} ms"


# ====================================================================== branches finishing apart

# data/chart_branches.elab, task every 10 ms, worked out by hand:
#   10   Idle entered (log 0 + 1 = 1)
#   50   go: Idle -> (A1, B1), shows at 60
#   100  a and b: A1 -> A2 and B1 -> B2 fire together: exits first (A1:
#        1 * 10, B1: + 100), then A2's entry (* 2): log 220 at 110
#   150  go off: the convergence fires (both A2 and B2 active): Idle at 160,
#        log 221
#   200  go again: A1+B1 at 210; 250 a: A2+B1 at 260, log 221 * 10 * 2
#   300  go off, but B1 still waits: no convergence
#   500  B1.time reaches 300 ms (entered at 200): B2 at 510 (log + 100),
#        and the convergence at 510: Idle at 520 (log + 1)
BRANCHES = [(0, ""), (10, "Idle"), (60, "A1+B1"), (110, "A2+B2"), (160, "Idle"), (210, "A1+B1"),
            (260, "A2+B1"), (510, "A2+B2"), (520, "Idle")]


def test_convergence_waits_for_every_branch(tmp_path):
    from native_testlib import SANITIZE, build, run

    exe = build(DATA / "chart_branches.elab", tmp_path / "build", cflags=SANITIZE)
    t = run(exe, tmp_path / "t.csv", duration="600ms", stimulus=DATA / "chart_branches.stimulus.csv").trace
    assert t.changes("C.active") == [(ms * 1000, steps) for ms, steps in BRANCHES]
    assert t.changes("log") == [(0, "0"), (10000, "1"), (110000, "220"), (160000, "221"), (260000, "4420"),
                                (510000, "4520"), (520000, "4521")]
