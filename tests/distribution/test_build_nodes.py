"""`easylab build` of a model of nodes: one program per node on its own
board (the AVR joints with their simulator), the round tables as JSON, and
each crossing channel's two ends in the generated C."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from easylab.ir.split import split
from easylab.pipeline import lower_file

ROBOT = Path(__file__).resolve().parents[2] / "examples" / "robot" / "robot.elab"


def easylab(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "easylab", *args], capture_output=True, text=True, timeout=300,
                          cwd=cwd)


def test_the_robot_builds_node_by_node(tmp_path):
    run = easylab("build", str(ROBOT), cwd=tmp_path)
    assert (run.returncode, run.stderr) == (0, ""), run.stdout
    out = tmp_path / "build" / "robot"
    assert run.stdout.splitlines()[-1] == "build/robot/rounds.json"
    assert "planner: build/robot/planner/robot.planner" in run.stdout.splitlines()
    assert "joint1: build/robot/joint1/robot.joint1.elf" in run.stdout.splitlines()
    assert (out / "planner" / "robot.planner").is_file()
    for joint in ("joint1", "joint2"):
        assert (out / joint / f"robot.{joint}.elf").is_file()
        assert (out / joint / f"robot.{joint}-sim").is_file()  # for `easylab launch`
    table = json.loads((out / "rounds.json").read_text())
    assert table["nodes"]["joint2"] == {"board": "avr", "mcu": "atmega328p"}
    (field,) = table["rounds"]
    assert (field["link"], field["master"], field["length_us"]) == ("field", "planner", 17097.22)
    assert [(s["node"], s["unit"], [b["channel"] for b in s["writes"]], [b["channel"] for b in s["reads"]])
            for s in field["slots"]] == [("joint1", 2, ["target1"], ["position1"]),
                                         ("joint2", 3, ["target2"], ["position2"])]


def test_each_end_of_a_crossing_channel_is_the_links(tmp_path):
    run = easylab("build", str(ROBOT), "-o", str(tmp_path / "b"))
    assert run.returncode == 0, run.stdout + run.stderr
    planner = (tmp_path / "b" / "planner" / "model.c").read_text()
    joint1 = (tmp_path / "b" / "joint1" / "model.c").read_text()
    # the planner produces target1 (the link pulls it) and consumes position1 (the link pushes it)
    program, _ = lower_file(ROBOT)
    nodes = split(program)
    target1 = next(c for c in nodes["planner"].program.channels if c.name == "target1")
    position1 = next(c for c in nodes["planner"].program.channels if c.name == "position1")
    assert f"uint16_t el_ch{target1.id}_pull(int16_t *tokens, uint16_t n)" in planner
    assert f"el_ch{target1.id}_take" not in planner
    assert f"uint16_t el_ch{position1.id}_push(const int16_t *tokens, uint16_t n)" in planner
    assert f"uint16_t el_ch{position1.id}_tardy;" in planner
    assert f"el_ch{position1.id}_put" not in planner
    assert "_pull(int16_t" in joint1 and "_push(const int16_t" in joint1


def test_an_output_end_starts_empty_the_initial_tokens_are_the_consumers():
    program, _ = lower_file(ROBOT)
    whole = {c.name: c for c in program.channels}
    nodes = split(program)
    sent = next(c for c in nodes["planner"].program.channels if c.name == "target1")
    received = next(c for c in nodes["joint1"].program.channels if c.name == "target1")
    assert sent.initial == [] and received.initial == whole["target1"].initial == [0, 0]


def test_a_model_without_nodes_is_not_built_node_by_node(tmp_path):
    from easylab.build import BuildError, build_nodes
    import pytest

    model = tmp_path / "one.elab"
    model.write_text("var x: int16\ntask t period 10 ms { }\n")
    program, result = lower_file(model)
    if program is None:
        pytest.fail(result.report())
    with pytest.raises(BuildError, match="model 'one' has no nodes: build it for one board"):
        build_nodes(program, tmp_path / "b")


def test_a_model_of_nodes_refuses_a_board_an_mcu_or_a_compiler_of_the_command_line(tmp_path):
    """Its nodes name their boards and MCUs (docs/distribution.md): --board,
    --mcu (and --cc) would be ignored, so the build refuses them, naming
    the nodes' own, before building anything."""
    for options in (["--board", "avr"], ["--board", "host"], ["--mcu", "atmega2560"],
                    ["--board", "avr", "--mcu", "atmega2560"], ["--cc", "clang"]):
        run = easylab("build", str(ROBOT), *options, "-o", str(tmp_path / "b"))
        assert run.returncode == 1 and run.stdout == "", (options, run.stdout, run.stderr)
        given = " and ".join(f"{options[i]} {options[i + 1]}" for i in range(0, len(options), 2))
        assert run.stderr == (
            f"easylab: error: {ROBOT}: model 'robot' has nodes, and each node names its board and MCU in the model "
            f"(planner on host, joint1 on avr (atmega328p), joint2 on avr (atmega328p)); {given} would choose for "
            f"all of them: build without {'it' if len(options) == 2 else 'them'}, or change a node's declaration "
            f"(`node NAME board B mcu M`, docs/distribution.md)\n"), options
        assert not (tmp_path / "b").exists()


def test_every_node_on_the_link_gets_the_round(tmp_path):
    run = easylab("build", str(ROBOT), "-o", str(tmp_path / "b"))
    assert run.returncode == 0, run.stdout + run.stderr
    master = (tmp_path / "b" / "planner" / "el_link.c").read_text()
    slave = (tmp_path / "b" / "joint2" / "el_link.c").read_text()
    assert "void el_round_master(uint64_t until_us, bool inclusive)" in master
    assert 'static const char *const el_lk_nodes[2] = { "joint1", "joint2" };' in master
    assert "int8_t el_round_gate(uint32_t tick)" in slave and "el_round_master" not in slave
    # the table's counts: nothing in round 0, then one value a round
    assert "= { 0, 1, 1 };" in slave


def test_a_slave_without_outputs_answers_its_status_alone(tmp_path):
    """j2 of the tests' arm only takes a value: the master's slot for it
    reads the status register alone (and compiles warning-free)."""
    from distribution_testlib import ROBOT as ARM

    model = tmp_path / "arm.elab"
    model.write_text(ARM)
    run = easylab("build", str(model), "-o", str(tmp_path / "b"))
    assert run.returncode == 0, run.stdout + run.stderr
    master = (tmp_path / "b" / "pc" / "el_link.c").read_text()
    slot = master[master.index("static void el_lk_slot1("):]
    assert "uint16_t w[1], i, n;" in slot[:200] and "answer[7]" in slot[:200]


def test_a_relay_between_two_slaves_is_not_built_yet(tmp_path):
    import pytest

    from distribution_testlib import ROBOT as TWO_SLAVES, variant
    from easylab.build import BuildError, build_nodes

    text = variant("channel pos1: int32 delay 2 over bus\n", "channel pos1: int32 delay 2 over bus\n"
                   "channel relay: int16 delay 2 over bus\n", TWO_SLAVES)
    text = variant("    e1 -> pos1\n", "    e1 -> pos1\n    g.y -> relay\n", text)
    text = variant("    g.y -> m2.speed\n", "    g.y -> m2.speed\n    relay -> seen2\n", text)
    text = variant("var seen: int32\n", "var seen: int32\nvar seen2: int16\n", text)
    path = tmp_path / "arm.elab"
    path.write_text(text)
    program, result = lower_file(path)
    assert program is not None, result.report()
    with pytest.raises(BuildError, match="channel 'relay' goes between two slaves of link 'bus': relaying it "
                                         "through the master is not built yet"):
        build_nodes(program, tmp_path / "b")
