"""`easylab launch` of the robot: the planner on the host, both joints in
simavr, the Modbus round over ptys, in lock-step and in real time. Each
node's trace equals, column by column, the single-node reference run of
the same model with its declared delays (`easylab run`); a joint killed
mid-run is reported by name and the others go on."""

from __future__ import annotations

import csv
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROBOT = Path(__file__).resolve().parents[2] / "examples" / "robot" / "robot.elab"
# the encoders move (the positions cross to the planner), the targets ramp (they cross to the joints)
STIMULUS = """time_us,encoder1.count,encoder2.count
0,0,0
100000,50,10
240000,120,-30
400000,-20,200
"""


def easylab(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "easylab", *args], capture_output=True, text=True, timeout=600,
                          cwd=cwd)


def rows(path: Path) -> list[list[str]]:
    with path.open(newline="") as f:
        return list(csv.reader(f))


def projected(reference: list[list[str]], columns: list[str]) -> list[list[str]]:
    """The reference trace's rows for some of its columns, a row where one
    of them changes (the traces' rule)."""
    at = [reference[0].index(c) for c in columns]
    out, last = [], None
    for row in reference[1:]:
        values = [row[i] for i in at]
        if values[1:] != last:
            out.append(values)
            last = values[1:]
    return out


def reference(tmp_path: Path, duration: str) -> list[list[str]]:
    run = easylab("run", str(ROBOT), "--fast", "--duration", duration, "--stimulus", "stimulus.csv",
                  "--trace", "reference.csv", cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    return rows(tmp_path / "reference.csv")


@pytest.mark.parametrize("pace", [["--fast"], pytest.param([], marks=pytest.mark.realtime)], ids=["lock-step", "real-time"])
def test_each_nodes_trace_equals_the_single_node_run(tmp_path, pace):
    (tmp_path / "stimulus.csv").write_text(STIMULUS)
    expected = reference(tmp_path, "600ms")
    run = easylab("launch", str(ROBOT), *pace, "--duration", "600ms", "--stimulus", "stimulus.csv",
                  "--trace-dir", "traces", cwd=tmp_path)
    assert run.returncode == 0, run.stdout + run.stderr
    assert "silent" not in run.stderr
    assert run.stdout.splitlines()[-3:] == ["planner: traces/planner.csv", "joint1: traces/joint1.csv",
                                            "joint2: traces/joint2.csv"]
    assert_each_node_follows(tmp_path / "traces", expected)


@pytest.mark.realtime
def test_a_real_time_launch_keeps_time_or_says_which_node_cannot(tmp_path):
    """The robot for 3 s in real time: the planner's task has no overrun,
    or the run says why, with figures: how long the round blocked the
    planner's loop and waiting for which slave, and each simulated slave
    that fell behind the wall clock with its pace. (The slaves' start-up is
    not owed by the run: the clock resumes after the bus's settle time.)"""
    import re

    run = easylab("launch", str(ROBOT), "--duration", "3s", "--trace-dir", "traces", cwd=tmp_path)
    assert run.returncode == 0, run.stdout + run.stderr
    late = re.search(r"robot\.planner: overruns: plan (\d+)", run.stderr)
    if late is None:
        return
    blocked = re.search(r"robot\.planner: bus: the round blocked this program's loop (\d+) ms of the (\d+) ms run "
                        r"\((\d+) %\): (\d+) ms of silence before frames \(EASYLAB_BUS_GAP_US\), (\d+) ms waiting for "
                        r"node 'joint1' \((\d+) answers, ([\d.]+) ms each\), (\d+) ms waiting for node 'joint2' "
                        r"\((\d+) answers, ([\d.]+) ms each\)", run.stderr)
    assert blocked, run.stderr
    total, run_ms, _, gaps, joint1, answers1, each1, joint2, answers2, each2 = map(float, blocked.groups())
    assert total == pytest.approx(gaps + joint1 + joint2, abs=3) and 0 < total <= run_ms
    for waited, answers, each in ((joint1, answers1, each1), (joint2, answers2, each2)):
        assert answers > 0 and waited == pytest.approx(answers * each, abs=answers * 0.05 + 1)
    for pace in re.finditer(r"robot\.(joint[12])-sim: the simulation fell (\d+) ms behind the wall clock in (\d+) ms "
                            r"of simulated time: this machine ran it at (\d\.\d\d)x real time", run.stderr):
        assert int(pace.group(2)) > 50 and 0 < float(pace.group(4)) < 1


def assert_each_node_follows(traces: Path, expected: list[list[str]]) -> None:
    """Each node's trace is the reference's for its columns, and the values
    crossed: the planner saw both joints move, each joint followed the
    planner's ramp."""
    for node, columns in (("planner", ["time_us", "amplitude", "spread"]),
                          ("joint1", ["time_us", "kp", "motor1.speed", "encoder1.count"]),
                          ("joint2", ["time_us", "kp", "motor2.speed", "encoder2.count"])):
        trace = rows(traces / f"{node}.csv")
        assert trace[0] == columns
        assert trace[1:] == projected(expected, columns), node
    assert [r[2] for r in rows(traces / "planner.csv")[1:]] == ["0", "40", "150", "-220"]


def pic18_elbow(text: str) -> str:
    """The robot with its elbow joint on a PIC18F4620 (CCP1's PWM, the
    encoder on INT0/INT1, the bus on its one EUSART)."""
    for old, new in (('node joint2  board avr mcu atmega328p', 'node joint2  board pic18 mcu pic18f4620'),
                     ('Motor(pwm = "PD6", dir = "PD7") on joint2', 'Motor(pwm = "RC2", dir = "RD6") on joint2'),
                     ('Encoder(pin_a = "PD2", pin_b = "PD4") on joint2',
                      'Encoder(pin_a = "RB0", pin_b = "RB1") on joint2')):
        assert old in text, old
        text = text.replace(old, new)
    return text


def test_slaves_on_different_boards_follow_one_round(tmp_path):
    """An AVR joint and a PIC18 joint (in gpsim) on one bus, relative
    build and trace folders: each node's trace still equals the
    single-node reference."""
    model = tmp_path / "robot.elab"
    model.write_text(pic18_elbow(ROBOT.read_text()))
    (tmp_path / "stimulus.csv").write_text(STIMULUS)
    run = easylab("run", str(model), "--fast", "--duration", "600ms", "--stimulus", "stimulus.csv",
                  "--trace", "reference.csv", cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    expected = rows(tmp_path / "reference.csv")
    run = easylab("launch", "robot.elab", "--fast", "--duration", "600ms", "--stimulus", "stimulus.csv",
                  "--trace-dir", "traces", "--build-dir", "build", cwd=tmp_path)
    assert run.returncode == 0, run.stdout + run.stderr
    assert (tmp_path / "build" / "joint2" / "robot.joint2.hex").exists()
    assert_each_node_follows(tmp_path / "traces", expected)


def test_a_killed_slave_is_reported_and_the_others_go_on(tmp_path):
    # the encoders move until the end, so that the planner misses joint2's last moves whenever it dies
    (tmp_path / "stimulus.csv").write_text(STIMULUS + "".join(f"{t * 1000000},{t * 10},{-t * 20}\n"
                                                              for t in range(1, 10)))
    expected = reference(tmp_path, "10s")
    launch = subprocess.Popen([sys.executable, "-m", "easylab", "launch", str(ROBOT), "--fast", "--duration", "10s",
                               "--stimulus", "stimulus.csv", "--trace-dir", "traces"], cwd=tmp_path,
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    pid_file = tmp_path / "traces" / "joint2.pid"
    deadline = time.monotonic() + 300
    while not pid_file.exists():
        assert launch.poll() is None and time.monotonic() < deadline, launch.communicate()
        time.sleep(0.01)
    time.sleep(1.0)  # some rounds on
    assert launch.poll() is None, "the run ended before joint2 could be stopped mid-run"
    os.kill(int(pid_file.read_text()), signal.SIGKILL)  # dead: its pty closes
    out, err = launch.communicate(timeout=600)
    assert launch.returncode == 0, out + err
    assert "easylab: node 'joint2' is silent on the bus" in err
    assert "'joint1' is silent" not in err
    assert "robot.planner: bus: node 'joint2' left " in err and "node 'joint1' left" not in err
    # joint1 and the planner went on to the end; joint1's values do not depend on joint2
    columns = ["time_us", "kp", "motor1.speed", "encoder1.count"]
    assert rows(tmp_path / "traces" / "joint1.csv")[1:] == projected(expected, columns)
    planner = rows(tmp_path / "traces" / "planner.csv")
    assert planner[1:] != projected(expected, planner[0])  # the planner kept joint2's last position


def test_a_killed_slaves_faults_are_on_the_masters_debug_interface(tmp_path):
    """`easylab launch --debug tcp:PORT` serves the planner's debug
    interface: its status items, read by id as any item, count the frames
    joint2 left unanswered once it is killed and the releases of `plan`
    that found no new position2 (tardy, the last value held), and none for
    joint1; the run goes on until the planner is stopped, and joint1's
    trace stays the single-node run's."""
    import socket

    from easylab.host_tools.debug_map import DebugMap
    from easylab.host_tools.debug_protocol import DebugClient

    (tmp_path / "stimulus.csv").write_text(STIMULUS + "".join(f"{t * 1000000},{t * 10},{-t * 20}\n"
                                                              for t in range(1, 20)))
    expected = reference(tmp_path, "20s")
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    launch = subprocess.Popen([sys.executable, "-m", "easylab", "launch", str(ROBOT), "--fast", "--duration", "600s",
                               "--stimulus", "stimulus.csv", "--trace-dir", "traces", "--debug", f"tcp:{port}"],
                              cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    client = None
    try:
        deadline = time.monotonic() + 300
        while client is None:
            assert launch.poll() is None and time.monotonic() < deadline, launch.communicate()
            try:
                client = DebugClient.open(f"socket://127.0.0.1:{port}", 2.0)
            except Exception:
                time.sleep(0.05)
        names = ("link.joint1.unanswered", "link.joint2.unanswered", "link.position1.tardy", "link.position2.tardy")
        dmap = DebugMap.load(tmp_path / "build" / "robot" / "planner" / "debug_map.json")
        items = [dmap.item(n) for n in names]
        assert all(i.kind == "status" and not i.writable for i in items)

        def counts() -> dict[str, int]:
            return dict(zip(names, client.read([(i.id, i.type, 1) for i in items])))

        assert counts()["link.joint2.unanswered"] == 0
        os.kill(int((tmp_path / "traces" / "joint2.pid").read_text()), signal.SIGKILL)
        while counts()["link.joint2.unanswered"] == 0 or counts()["link.position2.tardy"] == 0:
            assert launch.poll() is None and time.monotonic() < deadline, "no fault counted"
            time.sleep(0.02)
        seen = counts()
        assert seen["link.joint1.unanswered"] == 0 and seen["link.position1.tardy"] == 0
        client.close()
        client = None
        _the_online_page_reads_them(tmp_path / "build" / "robot" / "planner" / "debug_map.json", port, dmap, seen)
        # easylab-debug lists them with the other items (read-only, kind status) and reads them by name
        console = subprocess.run([sys.executable, "-m", "easylab.host_tools.debug_console", f"socket://127.0.0.1:{port}",
                                  "--map", str(tmp_path / "build" / "robot" / "planner" / "debug_map.json"),
                                  "--timeout", "5", "-c", "vars link.*; read link.joint2.unanswered"],
                                 capture_output=True, text=True, timeout=120)
        assert console.returncode == 0, console.stderr
        listed = [line.split() for line in console.stdout.splitlines() if line.startswith("link.")]
        assert [(w[0], w[1], w[2], w[3]) for w in listed if len(w) > 3 and w[1] == "uint16"] == [
            (name, "uint16", "status", "ro") for name in sorted(names, key=lambda n: dmap.item(n).id)]
        value = next(line for line in console.stdout.splitlines() if line.startswith("link.joint2.unanswered ="))
        assert int(value.split("=")[1]) >= seen["link.joint2.unanswered"]
        os.kill(int((tmp_path / "traces" / "planner.pid").read_text()), signal.SIGTERM)  # it ends normally
        out, err = launch.communicate(timeout=600)
    finally:
        if client is not None:
            client.close()
        if launch.poll() is None:
            launch.kill()
            launch.communicate()
    assert launch.returncode == 0, out + err
    assert "robot.planner: bus: node 'joint2' left " in err and "node 'joint1' left" not in err
    columns = ["time_us", "kp", "motor1.speed", "encoder1.count"]
    joint1 = rows(tmp_path / "traces" / "joint1.csv")[1:]
    assert len(joint1) > 3 and joint1 == projected(expected, columns)[:len(joint1)]  # up to the planner's stop
    planner = rows(tmp_path / "traces" / "planner.csv")
    assert planner[1:] != projected(expected, planner[0])[:len(planner) - 1]  # it kept joint2's last position


def _the_online_page_reads_them(map_path: Path, port: int, dmap, seen: dict[str, int]) -> None:
    """`easylab-debug web` against the launched master: its page's model is
    the robot's drawing, and its snapshots carry the status items (polled
    with whatever the page shows) counting joint2's silence."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "debug_web"))
    from onlinelib import OnlineServer, wait_for

    server = OnlineServer(map_path, f"tcp:127.0.0.1:{port}", model=None).start()
    try:
        model = server.model()
        assert any(el.startswith("step:") or el.startswith("actor:") for el in model["elements"]), model["elements"]
        unanswered = str(dmap.item("link.joint2.unanswered").id)

        def counted():
            snaps = server.state()["snapshots"]
            return snaps and unanswered in snaps[-1]["values"] and snaps[-1]["values"][unanswered]

        assert wait_for(counted, 60, "the planner's status items on the page") >= seen["link.joint2.unanswered"]
        assert not server.state()["snapshots"][-1]["halted"]
    finally:
        server.stop()


def test_a_model_without_nodes_is_not_launched(tmp_path):
    model = tmp_path / "one.elab"
    model.write_text("var x: int16\ntask t period 10 ms { }\n")
    run = easylab("launch", str(model), "--fast", "--duration", "100ms", cwd=tmp_path)
    assert run.returncode != 0
    assert "model 'one' has no nodes: run it with 'easylab run' or build it for a board" in run.stderr
    assert not (tmp_path / "build").exists()
