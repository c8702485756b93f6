"""A joint of the robot alone in simavr, its Modbus UART on a pty, spoken
to frame by frame: the round's sync lets its ticks run, its function-23
slot writes its input and reads its status and output, a slot of another
layout is refused, and other requests still go to its service map."""

from __future__ import annotations

import os
import select
import subprocess
import sys
import time
import tty
from pathlib import Path

import pytest

from easylab.core.crc import crc16

ROBOT = Path(__file__).resolve().parents[2] / "examples" / "robot" / "robot.elab"


def frame(*data: int) -> bytes:
    body = bytes(data)
    crc = crc16(body)
    return body + bytes([crc & 0xFF, crc >> 8])


@pytest.fixture
def joint(tmp_path):
    out = tmp_path
    run = subprocess.run([sys.executable, "-m", "easylab", "build", str(ROBOT), "-o", str(out)],
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stdout + run.stderr
    link = out / "joint1.bus"
    sim = subprocess.Popen([str(out / "joint1" / "robot.joint1-sim"), "--fast", "--wait", "--trace",
                            str(out / "joint1.csv"), "--uart0", f"pty:{link}"], stdin=subprocess.DEVNULL,
                           stderr=subprocess.PIPE)
    deadline = time.monotonic() + 30
    while not link.exists():
        assert sim.poll() is None and time.monotonic() < deadline
        time.sleep(0.02)
    fd = os.open(link, os.O_RDWR | os.O_NOCTTY)
    tty.setraw(fd)
    time.sleep(0.2)  # the firmware starts once its UART has a client
    yield fd, out, sim
    os.close(fd)
    if sim.poll() is None:
        sim.terminate()
        sim.wait(timeout=30)


def ask(fd: int, request: bytes, size: int) -> bytes:
    os.write(fd, request)
    answer, end = b"", time.monotonic() + 10
    while len(answer) < size and time.monotonic() < end:
        if select.select([fd], [], [], 0.05)[0]:
            answer += os.read(fd, 256)
    return answer


def test_the_sync_the_slot_a_wrong_slot_and_the_service_map(joint):
    fd, out, sim = joint
    # a confirmed sync of round 0 (to the slave's unit 2) is echoed
    sync = frame(2, 0x06, 0xE0, 0x00, 0x00, 0x00)
    assert ask(fd, sync, 8) == sync
    # slot: write target1 (one register at 0xE200), read status and position1 (two at 0xE100)
    slot = frame(2, 0x17, 0xE1, 0x00, 0x00, 0x02, 0xE2, 0x00, 0x00, 0x01, 0x02, 0x00, 0x07)
    assert ask(fd, slot, 9) == frame(2, 0x17, 0x04, 0x00, 0x00, 0x00, 0x00)  # round 0: nothing carried yet
    for number in (1, 2, 3):
        sync = frame(2, 0x06, 0xE0, 0x00, 0x00, number)
        assert ask(fd, sync, 8) == sync
        answer = ask(fd, slot, 9)
        # the status is the round taken; position1 (encoder 0) crosses from round 1 on
        assert answer == frame(2, 0x17, 0x04, 0x00, number, 0x00, 0x00)
    # a slot of another layout (three registers read) is exception 02, not a round's exchange
    wrong = frame(2, 0x17, 0xE1, 0x00, 0x00, 0x03, 0xE2, 0x00, 0x00, 0x01, 0x02, 0x00, 0x07)
    assert ask(fd, wrong, 5) == frame(2, 0x97, 0x02)
    # other requests are the service map's (the joint's map is empty: exception 02)
    assert ask(fd, frame(2, 0x03, 0x00, 0x00, 0x00, 0x01), 5) == frame(2, 0x83, 0x02)
    # a broadcast sync is not answered, and lets the ticks run on
    assert ask(fd, frame(0, 0x06, 0xE0, 0x00, 0x00, 0x04), 1) == b""
    answer = ask(fd, slot, 9)
    assert answer == frame(2, 0x17, 0x04, 0x00, 0x04, 0x00, 0x00)
    # the syncs let the joint run its instants up to its slot in round 4 (0 to 80 ms); the target 7
    # written from round 1 on is taken after the two initial tokens by the release at 40 ms, whose
    # output (the motor at 2 x 7) is published at its deadline, 60 ms
    sim.terminate()
    sim.wait(timeout=30)
    assert (out / "joint1.csv").read_text().splitlines() == [
        "time_us,kp,motor1.speed,encoder1.count", "0,2000,0,0", "60000,2000,14,0"]


def test_a_slave_serves_its_tardy_count_on_its_service_map(joint):
    """Rounds whose slot stops coming (the master's frames lost on the
    bus): the joint's releases find no new target1, keep the last one (its
    motor holds 2 x 7) and count it; the count is the input register of
    `link.target1.tardy` in the joint's service map, read with function 4
    at its unit id on the link, and the joint keeps answering."""
    import json

    fd, out, sim = joint
    entry = next(i for i in json.loads((out / "joint1" / "service_map.json").read_text())["items"]
                 if i["name"] == "link.target1.tardy")
    assert (entry["table"], entry["access"], entry["type"], entry["kind"]) == ("input", "ro", "uint16", "status")
    read = frame(2, 0x04, entry["address"] >> 8, entry["address"] & 0xFF, 0x00, 0x01)
    assert ask(fd, read, 7) == frame(2, 0x04, 0x02, 0x00, 0x00)  # nothing late before the rounds
    slot = frame(2, 0x17, 0xE1, 0x00, 0x00, 0x02, 0xE2, 0x00, 0x00, 0x01, 0x02, 0x00, 0x07)
    for number in range(8):  # rounds 0..7 (releases at 0 .. 140 ms); the slot, writing 7, in rounds 0..2 only
        sync = frame(2, 0x06, 0xE0, 0x00, 0x00, number)
        assert ask(fd, sync, 8) == sync
        if number <= 2:
            assert len(ask(fd, slot, 9)) == 9
    # the releases at 0 and 20 ms take the initial tokens, those at 40 and 60 ms the 7s of rounds 1 and 2;
    # the four at 80 .. 140 ms find none
    assert ask(fd, read, 7) == frame(2, 0x04, 0x02, 0x00, 0x04)
    # the counter is read-only: 06 writes holding registers, and the joint has none
    assert ask(fd, frame(2, 0x06, entry["address"] >> 8, entry["address"] & 0xFF, 0x00, 0x00), 5) == \
        frame(2, 0x86, 0x02)
    sim.terminate()
    sim.wait(timeout=30)
    # the motor follows the target 7 from the release at 40 ms (published at 60 ms) and holds it
    assert (out / "joint1.csv").read_text().splitlines() == [
        "time_us,kp,motor1.speed,encoder1.count", "0,2000,0,0", "60000,2000,14,0"]
