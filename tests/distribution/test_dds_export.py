"""DDS exports (docs/distribution.md, "DDS"): the topics and ROS 2 types in
each node's IR, the host build (libddsc only with exports, a clear error
without Cyclone DDS), and, in a private network namespace, an independent
subscriber (the PyPI cyclonedds binding, told only the ROS 2 topic and type
names) that receives every exported value, equal to the producing node's
trace at the same logical instants."""

from __future__ import annotations

import csv
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from easylab.core import types as T
from easylab.ir.dds import idl_text, ros_type_of
from easylab.ir.program import to_json
from easylab.ir.split import split
from easylab.pipeline import lower_file
from distribution_testlib import variant

ROOT = Path(__file__).resolve().parents[2]
ROBOT = ROOT / "examples" / "robot" / "robot.elab"
LISTENER = Path(__file__).resolve().parent / "ros2_listener.py"
sys.path.insert(0, str(ROOT / "tools"))
from netns import namespace_command, namespace_problem  # noqa: E402

DOMAIN = 42  # the test's own domain, in its own namespace
COUNTER = f"""\
model counter "a PC that publishes a ramp on DDS"
import std
node pc board host
link ros dds domain {DOMAIN} {{
    peer pc
}}
channel steps: int16 delay 1
var level: int16
var mirror: int16
dataflow Produce {{
    ramp = Ramp<int16>(slope = 3)
    ramp.y -> level
    ramp.y -> steps
}}
dataflow Consume {{
    steps -> mirror
}}
task produce on pc period 10 ms {{ run Produce }}
task consume on pc period 10 ms {{ run Consume }}
export level over ros
export steps over ros
"""


def easylab(*args: str, cwd: Path | None = None, env: dict | None = None) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "easylab", *args], capture_output=True, text=True, timeout=600,
                          cwd=cwd, env=env)


def counter_model(tmp_path: Path) -> Path:
    path = tmp_path / "counter.elab"
    path.write_text(COUNTER)
    return path


def trace(path: Path) -> tuple[list[str], list[list[int]]]:
    with path.open(newline="") as f:
        rows = list(csv.reader(f))
    return rows[0], [[int(v) for v in row] for row in rows[1:]]


def value_at(header: list[str], rows: list[list[int]], column: str, t_us: int) -> int:
    """The traced value of ``column`` at ``t_us`` (a row is written when a value changes)."""
    col = header.index(column)
    return [row[col] for row in rows if row[0] <= t_us][-1]


def in_namespace(tmp_path: Path, listeners: dict[str, list[str]], node: list[str], timeout: float = 300):
    """Starts each listener (name -> its arguments) in a private network
    namespace, waits until each has its reader, runs ``node`` there, and
    returns each listener's samples as (source timestamp in µs, data)."""
    problem = namespace_problem()
    if problem:
        pytest.fail(f"the DDS acceptance test runs in a private network namespace: {problem}")
    lines = []
    for n, (name, args) in enumerate(listeners.items()):
        cmd = " ".join(map(_quote, [sys.executable, str(LISTENER), "--transient-local", *args]))
        lines.append(f"{cmd} > {_quote(str(tmp_path / name))}.jsonl & listener{n}=$!")
    for n, name in enumerate(listeners):  # a listener that dies before it is ready ends the run at once
        lines.append(f"until grep -q ready {_quote(str(tmp_path / name))}.jsonl; do kill -0 $listener{n} 2>/dev/null "
                     f"|| {{ echo 'the listener {name} ended before it was ready' >&2; exit 3; }}; sleep 0.05; done")
    lines += [" ".join(map(_quote, node)) + " > node.out 2>&1; echo $? > node.rc", "wait"]
    proc = subprocess.run(namespace_command(["sh", "-c", "\n".join(lines)]), cwd=tmp_path, capture_output=True,
                          text=True, timeout=timeout)
    node_out = (tmp_path / "node.out").read_text() if (tmp_path / "node.out").exists() else ""
    assert proc.returncode == 0 and (tmp_path / "node.rc").read_text().strip() == "0", \
        proc.stdout + proc.stderr + node_out
    samples = {}
    for name in listeners:
        got = (tmp_path / f"{name}.jsonl").read_text().splitlines()
        assert got[0] == "ready"
        samples[name] = [(s["t"] // 1000, s["data"]) for s in map(json.loads, got[1:])]
    return samples


def _quote(text: str) -> str:
    return "'" + text.replace("'", "'\\''") + "'"


def listener_args(topic: str, type_name: str, field: str) -> list[str]:
    return ["--domain", str(DOMAIN), "--topic", topic, "--type", type_name, "--field", field, "--seconds", "120",
            "--idle", "2"]


# ---------------------------------------------------------------- the IR


def test_each_node_program_carries_its_exports_topics_and_ros2_types(tmp_path):
    program, result = lower_file(counter_model(tmp_path))
    assert program is not None, result.report()
    pc = split(program)["pc"].program
    assert [(e.name, e.kind, e.topic, e.domain, e.type_name, e.ros_type, e.values) for e in pc.exports] == [
        ("level", "var", "rt/counter/pc/level", DOMAIN, "std_msgs::msg::dds_::Int16_", "std_msgs/msg/Int16", 1),
        ("steps", "channel", "rt/counter/pc/steps", DOMAIN, "std_msgs::msg::dds_::Int16_", "std_msgs/msg/Int16", 1)]
    produce, consume = (next(t.id for t in pc.tasks if t.name == n) for n in ("produce", "consume"))
    # a var at its writer's publication, a channel at its consumer's release
    assert [e.trigger_tasks for e in pc.exports] == [[produce], [consume]]
    assert pc.exports[0].target == pc.item("level").id
    assert to_json(pc)["exports"][0]["topic"] == "rt/counter/pc/level"  # in the IR's dump and id

    robot, _ = lower_file(ROBOT)
    nodes = split(robot)
    (position1,) = nodes["planner"].program.exports
    assert (position1.topic, position1.type_name) == ("rt/robot/planner/position1", "std_msgs::msg::dds_::Int16_")
    assert nodes["joint1"].program.exports == [] and "exports" not in to_json(nodes["joint1"].program)


def test_a_value_std_msgs_lacks_gets_a_struct_of_the_models_own():
    assert ros_type_of("arm", "speed_set", T.FLOAT32, 1) == (("std_msgs", "msg", "dds_"), "Float32_", "float")
    assert ros_type_of("arm", "speed_set", T.FLOAT32, 3) == (("arm", "msg", "dds_"), "SpeedSet_", "float")
    assert ros_type_of("arm", "when", T.TIME, 1) == (("arm", "msg", "dds_"), "When_", "unsigned long")
    program, _ = lower_file(ROBOT)
    export = split(program)["planner"].program.exports[0]
    assert "@final struct Int16_ { short data; };" in idl_text([export, export])
    assert idl_text([export, export]).count("struct") == 1  # each type once


# ---------------------------------------------------------------- the build


def _links_libddsc(exe: Path) -> bool:
    return "libddsc" in subprocess.run(["ldd", str(exe)], capture_output=True, text=True, check=True).stdout


def test_only_a_node_with_exports_links_libddsc(tmp_path):
    run = easylab("build", str(counter_model(tmp_path)), "-o", str(tmp_path / "b"))
    assert run.returncode == 0, run.stdout + run.stderr
    assert _links_libddsc(tmp_path / "b" / "pc" / "counter.pc")
    assert "std_msgs_msg_dds__Int16_" in (tmp_path / "b" / "pc" / "el_dds_types.h").read_text()
    no_exports = tmp_path / "quiet.elab"
    no_exports.write_text(COUNTER.replace("export level over ros\nexport steps over ros\n", ""))
    run = easylab("build", str(no_exports), "-o", str(tmp_path / "q"))
    assert run.returncode == 0, run.stdout + run.stderr
    assert not _links_libddsc(tmp_path / "q" / "pc" / "counter.pc")
    assert not (tmp_path / "q" / "pc" / "el_dds_types.idl").exists()
    assert "el_port_export" not in (tmp_path / "q" / "pc" / "model.c").read_text()


def test_exports_without_cyclone_dds_say_what_to_install(tmp_path):
    # A PATH with the C compiler and pkg-config but without idlc.
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    for tool in ("gcc", "pkg-config", "size"):
        os.symlink(shutil.which(tool), bin_dir / tool)
    env = {**os.environ, "PATH": str(bin_dir)}
    run = easylab("build", str(counter_model(tmp_path)), "-o", str(tmp_path / "b"), env=env)
    assert run.returncode != 0
    assert "exports over DDS need Eclipse Cyclone DDS (libddsc and idlc): install the Debian packages " \
           "cyclonedds-dev and cyclonedds-tools" in run.stderr, run.stderr


def test_an_export_on_a_board_without_dds_is_an_error_naming_the_node(tmp_path):
    model = _write(tmp_path / "arm.elab", variant("    peer pc\n}", "    peer pc\n    peer j1\n}").replace(
        "export pos1 over lan", "var level: int32\nexport level over lan").replace(
        "    e1 -> pos1\n", "    e1 -> pos1\n    e1 -> level\n"))
    expected = ("node 'j1': a DDS peer with exports or channels needs a board with DDS (board.toml: dds = true), "
                "and board 'avr' has none: put them on a PC node")
    check = easylab("check", str(model))
    assert check.returncode != 0 and "node 'j1' (board avr, atmega328p): a DDS peer" in check.stdout + check.stderr
    run = easylab("build", str(model), "-o", str(tmp_path / "b"))
    assert run.returncode != 0 and expected in run.stderr, run.stdout + run.stderr
    assert not (tmp_path / "b" / "pc").exists()  # refused before any node is built


# ---------------------------------------------------------------- on the wire


@pytest.mark.realtime  # the node runs in real time: a subscriber starved by a loaded machine loses samples
def test_an_independent_ros2_subscriber_receives_every_exported_value(tmp_path):
    run = easylab("build", str(counter_model(tmp_path)), "-o", str(tmp_path / "b"))
    assert run.returncode == 0, run.stdout + run.stderr
    exe = tmp_path / "b" / "pc" / "counter.pc"
    int16 = "std_msgs::msg::dds_::Int16_"
    got = in_namespace(tmp_path, {"level": listener_args("rt/counter/pc/level", int16, "int16"),
                                  "steps": listener_args("rt/counter/pc/steps", int16, "int16")},
                       [str(exe), "--duration", "1s", "--trace", "pc.csv"])
    header, rows = trace(tmp_path / "pc.csv")
    # level: at each publication of `produce` (10 ms, 20 ms, ... up to the end), the traced value then
    assert [t for t, _ in got["level"]] == list(range(10_000, 1_000_000, 10_000))
    assert got["level"] == [(t, value_at(header, rows, "level", t)) for t, _ in got["level"]]
    assert got["level"][:3] == [(10_000, 3), (20_000, 6), (30_000, 9)]
    # steps: at each release of `consume` (from 0), the token it takes, which
    # `consume` publishes as `mirror` at its deadline, one period later
    assert [t for t, _ in got["steps"]] == list(range(0, 1_000_000, 10_000))
    # (the run ends at 1 s: the last token's `mirror` is not traced)
    assert got["steps"][:-1] == [(t, value_at(header, rows, "mirror", t + 10_000)) for t, _ in got["steps"][:-1]]
    assert got["steps"][-1] == (990_000, got["level"][-1][1])  # taken at 990 ms, published at 990 ms
    assert len({v for _, v in got["steps"]}) == len(got["steps"])  # a ramp: the sequence, not one value


ENCODERS = """time_us,encoder1.count,encoder2.count
0,0,0
100000,50,10
240000,120,-30
400000,-20,200
"""


def test_the_robots_export_reaches_a_ros2_subscriber_with_the_joints_values(tmp_path):
    # the robot example in its own domain: planner on the host, both joints in simavr, in lock-step
    (tmp_path / "robot.elab").write_text(ROBOT.read_text().replace("link ros dds domain 0", f"link ros dds domain {DOMAIN}"))
    (tmp_path / "stimulus.csv").write_text(ENCODERS)
    args = [*listener_args("rt/robot/planner/position1", "std_msgs::msg::dds_::Int16_", "int16")]
    args[args.index("--idle") + 1] = "10"  # the build comes first
    got = in_namespace(tmp_path, {"position1": args},
                       [sys.executable, "-m", "easylab", "launch", "robot.elab", "--fast", "--duration", "600ms",
                        "--stimulus", "stimulus.csv", "--trace-dir", "traces", "--build-dir", "build"],
                       timeout=900)["position1"]
    joint1 = trace(tmp_path / "traces" / "joint1.csv")
    joint2 = trace(tmp_path / "traces" / "joint2.csv")
    planner = trace(tmp_path / "traces" / "planner.csv")
    # at each release of `plan` (every 20 ms from 0) the token it takes: the
    # encoder count `control1` read two periods before (delay 2; 0 before)
    assert [t for t, _ in got] == list(range(0, 600_000, 20_000))

    def position(joint, column, t):
        return 0 if t < 40_000 else (value_at(*joint, column, t - 40_000) + 2 ** 15) % 2 ** 16 - 2 ** 15

    assert got == [(t, position(joint1, "encoder1.count", t)) for t, _ in got]
    assert {v for _, v in got} == {0, 50, 120, -20}
    # and `plan` computed its spread from that very value, published one period later
    assert all(value_at(*planner, "spread", t + 20_000) == v - position(joint2, "encoder2.count", t)
               for t, v in got[:-1])


# ---------------------------------------------------------------- channels between two PCs

PAIR = """\
model pair "two PCs: a ramp crosses DDS"
import std
node a board host
node b board host
link lan dds domain 44 latency 5 ms {
    peer a
    peer b
}
channel steps: int16 delay 2 over lan
var mirror: int16
dataflow Produce {
    ramp = Ramp<int16>(slope = 3)
    ramp.y -> steps
}
dataflow Consume {
    steps -> mirror
}
task produce on a period 10 ms { run Produce }
task consume on b period 10 ms offset 3 ms { run Consume }
"""


def test_a_channel_over_dds_needs_the_delay_its_links_latency_asks(tmp_path):
    model = tmp_path / "pair.elab"
    model.write_text(PAIR.replace("delay 2 over", "delay 1 over"))
    check = easylab("check", str(model))
    assert check.returncode != 0
    assert "a value reaches task 'consume' up to 5000 us after task 'produce' publishes it; it needs 1 more " \
           "initial token(s)" in check.stderr + check.stdout
    program, _ = lower_file(_write(tmp_path / "ok.elab", PAIR))
    nodes = split(program)
    (out,), (end,) = nodes["a"].program.dds_channels, nodes["b"].program.dds_channels
    assert (out.direction, end.direction, out.topic, end.topic) == ("out", "in", "rt/pair/a/steps", "rt/pair/a/steps")
    # published at produce's deadlines (10 ms, 20 ms, ...), usable 5 ms later
    assert (end.delay_us, end.first_us, end.period_us, end.values) == (5000, 10_000, 10_000, 1)
    assert nodes["a"].program.exports == [] == nodes["b"].program.exports


def _write(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


@pytest.mark.parametrize("pace", [["--fast"], pytest.param([], marks=pytest.mark.realtime)],
                         ids=["lock-step", "real-time"])
def test_two_pcs_over_dds_trace_the_single_node_run(tmp_path, pace):
    model = _write(tmp_path / "pair.elab", PAIR)
    ref = easylab("run", str(model), "--fast", "--duration", "1s", "--trace", str(tmp_path / "reference.csv"))
    assert ref.returncode == 0, ref.stderr
    problem = namespace_problem()
    if problem:
        pytest.fail(f"the DDS channel test runs in a private network namespace: {problem}")
    run = subprocess.run(namespace_command([sys.executable, "-m", "easylab", "launch", "pair.elab", *pace,
                                            "--duration", "1s", "--trace-dir", "traces", "--build-dir", "build"]),
                         cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stdout + run.stderr
    assert "DDS" not in run.stderr, run.stderr  # no timeout, no lost token
    ref_header, reference = trace(tmp_path / "reference.csv")
    header, rows = trace(tmp_path / "traces" / "b.csv")
    # node b's trace starts at its first instant (3 ms), the whole model's at 0: the same values from there
    assert header == ref_header and rows[0] == [3000, *reference[0][1:]]
    assert rows[1:] == reference[1:]
    assert len(rows) > 90 and rows[1] == [33_000, 3]  # published at 10 ms, taken at 23 ms, mirrored at 33 ms


MULTI = """\
model multi
import std
node pc board host
link ros dds domain 42 {
    peer pc
}
channel fine_steps: int16 delay 2
var got: int16
dataflow P {
    r = Ramp<int16>(slope = 1)
    r.y -> fine_steps
}
dataflow C {
    d = Downsample<int16>(factor = 2)
    fine_steps -> d.x
    d.y -> got
}
task p on pc period 10 ms { run P }
task c on pc period 20 ms { run C }
export fine_steps over ros
"""


@pytest.mark.realtime  # (as above)
def test_several_tokens_per_release_are_one_sample_of_the_models_own_type(tmp_path):
    run = easylab("build", str(_write(tmp_path / "multi.elab", MULTI)), "-o", str(tmp_path / "b"))
    assert run.returncode == 0, run.stdout + run.stderr
    assert "@final struct FineSteps_ { short data[2]; };" in (tmp_path / "b" / "pc" / "el_dds_types.idl").read_text()
    args = ["--domain", str(DOMAIN), "--topic", "rt/multi/pc/fine_steps", "--type", "multi::msg::dds_::FineSteps_",
            "--field", "int16", "--length", "2", "--seconds", "120", "--idle", "2"]
    got = in_namespace(tmp_path, {"fine": args}, [str(tmp_path / "b" / "pc" / "multi.pc"), "--duration", "200ms",
                                                  "--trace", "pc.csv"])["fine"]
    # each release of c (every 20 ms) takes two tokens: the initial two, then the ramp's pairs
    assert got == [(t, [0, 0] if t == 0 else [t // 10_000 - 1, t // 10_000]) for t in range(0, 200_000, 20_000)]
    header, rows = trace(tmp_path / "pc.csv")
    assert all(value_at(header, rows, "got", t + 20_000) == v[1] for t, v in got[:-1])  # Downsample keeps the last
