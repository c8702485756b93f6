"""The robot example (examples/robot/robot.elab): three nodes, one Modbus
bus, one export on DDS; it checks clean, its round fits, and it is built node by node."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from easylab.ir.split import split
from easylab.pipeline import lower_file

ROBOT = Path(__file__).resolve().parents[2] / "examples" / "robot" / "robot.elab"


def easylab(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "easylab", *args], capture_output=True, text=True, timeout=120)


def test_the_robot_checks_clean():
    run = easylab("check", str(ROBOT))
    assert (run.returncode, run.stderr) == (0, "")
    assert run.stdout == f"{ROBOT}: ok (model 'robot': 4 devices, 3 dataflows, 0 charts, 3 tasks)\n"


def test_the_robot_splits_into_its_three_nodes():
    program, result = lower_file(ROBOT)
    assert program is not None, result.report()
    nodes = split(program)
    assert {n: (p.node.board, p.node.mcu) for n, p in nodes.items()} == {
        "planner": ("host", None), "joint1": ("avr", "atmega328p"), "joint2": ("avr", "atmega328p")}
    assert [t.name for t in nodes["joint1"].program.tasks] == ["control1"]
    assert [e.name for e in nodes["planner"].outputs] == ["target1", "target2"]
    assert [e.name for e in nodes["planner"].inputs] == ["position1", "position2"]
    table = program.deployment.rounds["field"]
    assert [(s.node, s.unit) for s in table.slots] == [("joint1", 2), ("joint2", 3)]
    # each joint: one int16 written, the status register and one int16 read: 15 + 9 characters a slot
    assert [(s.write_registers, s.read_registers) for s in table.timing.slots] == [(1, 2), (1, 2)]
    assert table.timing.slots[0].length_us == 24 * table.timing.character_us + 2 * 1750 + 1000  # 6791.67 us
    assert round(float(table.timing.length_us), 2) == 17097.22  # 3513.89 + 2 x 6791.67 us, within 20 ms
    assert [e.topic for e in program.deployment.exports] == ["rt/robot/planner/position1"]


def test_a_model_of_nodes_is_not_built_as_one_program(tmp_path):
    from easylab.build import BuildError, build
    import pytest

    program, _ = lower_file(ROBOT)
    with pytest.raises(BuildError, match="model 'robot' has nodes: it is built node by node"):
        build(program, "host", tmp_path / "b")


def test_analyze_shows_the_round():
    run = easylab("analyze", str(ROBOT))
    assert run.returncode == 0, run.stderr
    text = run.stdout[run.stdout.index("link field"):]
    assert text.splitlines() == [
        "link field (Modbus RTU, master planner): a round every 20000 us at 115200 baud takes 17097.22 us",
        "  character 95.49 us, t3.5 1750.0 us, turnaround 1000 us, sync error 190.97 us",
        "  sync                 0.00 us  +3513.89 us  broadcast round number to 0xE000",
        "  slot joint1 (unit 2, uart[0])  3513.89 us  +6791.67 us  writes target1 0xE200 (1); "
        "reads status 0xE100 (1), position1 0xE101 (1)",
        "  slot joint2 (unit 3, uart[0])  10305.56 us  +6791.67 us  writes target2 0xE200 (1); "
        "reads status 0xE100 (1), position2 0xE101 (1)"]
    import json
    data = json.loads(easylab("analyze", "--json", str(ROBOT)).stdout)
    assert [(s["node"], s["start_us"], s["length_us"]) for s in data["rounds"][0]["slots"]] == [
        ("joint1", 3513.89, 6791.67), ("joint2", 10305.56, 6791.67)]
