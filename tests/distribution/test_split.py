"""The split of a distributed program into one program per node, the round
table it carries, and each node's program against its board."""

from __future__ import annotations

import subprocess
import sys

import pytest

from easylab.analysis.distribution import READ_BASE, WRITE_BASE
from easylab.board.nodes import node_problems
from easylab.ir.program import to_json
from easylab.ir.split import split
from easylab.pipeline import lower_file
from distribution_testlib import ROBOT, variant


def lowered(tmp_path, text: str = ROBOT):
    path = tmp_path / "arm.elab"
    path.write_text(text)
    program, result = lower_file(path)
    assert program is not None, result.report()
    return program


def test_each_node_gets_its_tasks_devices_items_and_channel_ends(tmp_path):
    nodes = split(lowered(tmp_path))
    assert list(nodes) == ["pc", "j1", "j2"]
    pc, j1, j2 = (nodes[n].program for n in ("pc", "j1", "j2"))
    assert [t.name for t in pc.tasks] == ["plan"] and pc.devices == []
    assert [t.name for t in j1.tasks] == ["c1"] and [d.path for d in j1.devices] == ["m1", "e1"]
    assert [t.name for t in j2.tasks] == ["c2"] and [d.path for d in j2.devices] == ["m2"]
    assert [i.name for i in pc.items] == ["seen"]
    assert [(i.id, i.name, i.device) for i in j1.items] == [(0, "m1.speed", 0), (1, "e1.count", 1)]
    # ids are the node's own, numbered from 0, and every reference follows them
    assert [(d.id, d.items, d.read_by, d.written_by) for d in j1.devices] == [(0, [0], [], 0), (1, [1], [0], None)]
    assert [df.name for df in j1.dataflows] == ["J1"] and j1.dataflows[0].task == 0
    assert [(c.name, c.producer_task, c.consumer_task) for c in pc.channels] == [
        ("goal1", 0, None), ("goal2", 0, None), ("pos1", None, 0)]
    assert [(c.name, c.producer_task, c.consumer_task) for c in j1.channels] == [("goal1", None, 0), ("pos1", 0, None)]
    assert [(e.name, e.channel, e.link, e.other_node) for e in nodes["pc"].outputs] == [
        ("goal1", 0, "bus", "j1"), ("goal2", 1, "bus", "j2")]
    assert [(e.name, e.channel, e.other_node) for e in nodes["pc"].inputs] == [("pos1", 2, "j1")]
    assert [(e.name, e.channel) for e in nodes["j1"].inputs] == [("goal1", 0)]
    assert [(e.name, e.channel) for e in nodes["j1"].outputs] == [("pos1", 1)]
    externals = {(e.kind, e.target) for df in j1.dataflows for e in df.externals}
    assert externals == {("channel", 0), ("channel", 1), ("item", 0), ("item", 1)}
    assert len({j1.program_id, j2.program_id, pc.program_id}) == 3


def test_each_node_dispatches_its_own_tasks(tmp_path):
    nodes = split(lowered(tmp_path))
    j2 = nodes["j2"].program
    # c2: period 20 ms, offset 5 ms, deadline 5 ms: a 5 ms tick, 4 ticks in its hyperperiod
    assert (j2.tick_us, j2.hyperperiod) == (5000, 4)
    assert [(t.period, t.offset, t.deadline) for t in j2.tasks] == [(4, 1, 1)]
    assert [(i.tick, i.publish, i.release) for i in j2.instants] == [(1, [], [0]), (2, [0], [])]
    pc = nodes["pc"].program
    assert (pc.tick_us, pc.hyperperiod) == (20000, 1)
    assert [(i.tick, i.publish, i.release) for i in pc.instants] == [(0, [0], [0])]


def test_a_slave_is_a_modbus_rtu_slave_on_its_uart(tmp_path):
    nodes = split(lowered(tmp_path))
    assert [(i.kind, i.resource, i.settings) for i in nodes["j1"].program.interfaces] == [
        ("modbus-rtu", "uart[0]", {"baud": 115200, "parity": "even", "unit": 2})]
    # the master serves its status items on a debug interface of its own (no resource: where its
    # process is told); a slave on its Modbus RTU slave
    assert [(i.kind, i.resource, i.settings) for i in nodes["pc"].program.interfaces] == [("debug", None, {})]


def test_each_node_gets_the_status_items_of_its_links(tmp_path):
    """Tardy counters for the channels that cross to a node, one unanswered
    counter per slave on the master, in slot order; read-only uint16s that
    appear on the node's debug map and in its service map's input
    registers. A program without nodes has none (its dump is as before)."""
    from easylab.codegen.service import build_map, map_json

    program = lowered(tmp_path)
    assert program.status == [] and "status" not in to_json(program)
    nodes = split(program)
    pc, j1, j2 = (nodes[n].program for n in ("pc", "j1", "j2"))
    assert [(s.name, s.fault, s.subject, s.type.name, s.service) for s in pc.status] == [
        ("link.pos1.tardy", "tardy", 2, "uint16", "ro"), ("link.j1.unanswered", "unanswered", 0, "uint16", "ro"),
        ("link.j2.unanswered", "unanswered", 1, "uint16", "ro")]
    assert [s.name for s in j1.status] == ["link.goal1.tardy"] and [s.name for s in j2.status] == ["link.goal2.tardy"]
    entries = [(i["name"], i["table"], i["access"], i["kind"]) for i in map_json(build_map(j1))["items"]]
    assert entries[-1] == ("link.goal1.tardy", "input", "ro", "status")
    assert "status" in to_json(pc) and len({pc.program_id, j1.program_id}) == 2


def test_the_round_table(tmp_path):
    program = lowered(tmp_path)
    table = program.deployment.rounds["bus"]
    assert (table.link, table.master) == ("bus", "pc")
    assert [(s.node, s.unit, s.uart) for s in table.slots] == [("j1", 2, "uart[0]"), ("j2", 3, "uart[0]")]
    j1, j2 = table.slots
    # goal1 (int16) is written to j1 from offset 0; pos1 (int32) read after the status register
    assert [(b.channel, b.offset, b.registers) for b in j1.writes] == [("goal1", 0, 1)]
    assert [(b.channel, b.offset, b.registers, b.per_value) for b in j1.reads] == [("pos1", 1, 2, 2)]
    assert [(b.channel, b.offset) for b in j2.writes] == [("goal2", 0)] and j2.reads == ()
    assert [(s.write_registers, s.read_registers) for s in table.timing.slots] == [(1, 3), (1, 1)]
    assert WRITE_BASE != READ_BASE
    assert split(program)["pc"].rounds == [table] == split(program)["j2"].rounds
    exports = program.deployment.exports
    assert [(e.name, e.kind, e.node, e.topic) for e in exports] == [("pos1", "channel", "pc", "rt/arm/pc/pos1")]


def test_a_model_without_nodes_has_no_deployment_and_cannot_be_split(tmp_path):
    program = lowered(tmp_path, "model one\nimport std\nvar v: int16\ndataflow D {\n"
                                "    r = Ramp<int16>(slope = 1)\n    r.y -> v\n}\ntask t period 10 ms { run D }\n")
    assert program.deployment is None and "deployment" not in to_json(program)
    with pytest.raises(ValueError, match="model 'one' has no nodes"):
        split(program)


def test_every_node_fits_its_board(tmp_path):
    assert node_problems(lowered(tmp_path)) == []


def test_a_node_whose_board_lacks_a_resource_is_named_with_its_board(tmp_path):
    text = variant('device m1: Motor(pwm = "PD6", dir = "PD7") on j1', 'device m1: Motor(pwm = "PD6", dir = "PD1") on j1')
    problems = node_problems(lowered(tmp_path, text))
    assert len(problems) == 1
    # PD1 is the TX line of uart0, which the link's slave interface holds on j1
    assert problems[0].startswith("node 'j1' (board avr, atmega328p): the model does not fit the avr board")
    assert "pin PD1 is claimed twice on the atmega328p: as uart[0] by interface 'modbus rtu' and as pin[\"PD1\"] by device 'm1' (" in problems[0]
    assert problems[0].endswith("arm.elab:14); each pin has one owner: choose another pin, channel or UART")


def test_easylab_check_reports_the_nodes_that_do_not_fit(tmp_path):
    text = variant('device m2: Motor(pwm = "PD6", dir = "PD7") on j2', 'device m2: Motor(pwm = "PB3", dir = "PD7") on j2')
    path = tmp_path / "arm.elab"
    path.write_text(text)
    run = subprocess.run([sys.executable, "-m", "easylab", "check", str(path)], capture_output=True, text=True)
    assert run.returncode == 1
    assert run.stderr.startswith("node 'j2' (board avr, atmega328p): the model does not fit")
    assert f"{path}:15: error: device 'm2' claims pwm[\"PB3\"]" in run.stderr


def test_an_unknown_board_or_mcu_of_a_node_is_named(tmp_path):
    text = variant("node j2 board avr mcu atmega328p", "node j2 board avr mcu atmega9")
    problems = node_problems(lowered(tmp_path, text))
    assert len(problems) == 1 and problems[0].startswith("node 'j2' (board avr, atmega9): ")
    assert "atmega9" in problems[0].split(": ", 1)[1]


def test_a_channel_between_two_slaves_takes_a_slot_of_each(tmp_path):
    text = variant("channel pos1: int32 delay 2 over bus\n", "channel pos1: int32 delay 2 over bus\n"
                   "channel relay: int16 delay 2 over bus\n")
    text = variant("    e1 -> pos1\n", "    e1 -> pos1\n    g.y -> relay\n", text)
    text = variant("    g.y -> m2.speed\n", "    g.y -> m2.speed\n    relay -> seen2\n", text)
    text = variant("var seen: int32\n", "var seen: int32\nvar seen2: int16\n", text)
    program = lowered(tmp_path, text)
    j1, j2 = program.deployment.rounds["bus"].slots
    assert [(b.channel, b.offset, b.registers) for b in j1.reads] == [("pos1", 1, 2), ("relay", 3, 1)]
    assert [(b.channel, b.offset, b.registers) for b in j2.writes] == [("goal2", 0, 1), ("relay", 1, 1)]
    nodes = split(program)
    assert [(e.name, e.other_node) for e in nodes["j1"].outputs] == [("pos1", "pc"), ("relay", "j2")]
    assert [(e.name, e.other_node) for e in nodes["j2"].inputs] == [("goal2", "pc"), ("relay", "j1")]
    assert "relay" not in [c.name for c in nodes["pc"].program.channels]
