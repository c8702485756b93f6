"""The online mode's snapshots (host_tools/debug_web/target.py) against a
host firmware, over seeded random sets of items (the benchmark's model of
100 vars, and pneumatic_cylinder's items of every kind): a halted program
is read with plain reads and gives what the console's reads give; a running
one is read in one transaction (one instant) exactly when the items fit in
one, else frame by frame (`split`), every item with a value either way; a
wrong guess of the program's state is corrected; at every breakpoint on a
transition the firmware takes, the guard evaluated on the snapshot holds;
the elements' table names only probe points and items of the map."""

from __future__ import annotations

import random
import sys
import time

import pytest

from debug_testlib import ROOT, build, builds, firmware, transition_halts  # noqa: F401 (fixtures)

from easylab.host_tools.debug_map import DebugMap
from easylab.host_tools.debug_protocol import K
from easylab.host_tools.debug_web.elements import element_ids, elements, render_svg
from easylab.host_tools.debug_web.target import TargetLink, fits_one_transaction, target_url

sys.path.insert(0, str(ROOT / "bench"))
from bench_debug_web import bench_model  # noqa: E402

SEED = 29
ROUNDS = 40


@pytest.fixture(scope="module")
def many_vars(tmp_path_factory):
    """A host build of the benchmark's model (100 int16 vars, v0 counting)."""
    d = tmp_path_factory.mktemp("bench_online")
    model = d / "bench_online.elab"
    model.write_text(bench_model(100))
    return build(model, d / "host")


def random_sets(dmap: DebugMap, rng: random.Random):
    """Random item sets: small and large, in any order."""
    items = [it for it in dmap.items]
    for _ in range(ROUNDS):
        n = rng.choice([1, 2, rng.randint(3, 24), rng.randint(1, len(items))])
        yield rng.sample(items, min(n, len(items)))


@pytest.mark.parametrize("model", ["many_vars", "pneumatic_cylinder"])
def test_snapshots_of_random_item_sets(model, many_vars, builds, firmware):
    exe = many_vars if model == "many_vars" else builds["pneumatic_cylinder"]
    fw = firmware(exe, halt=True)
    client = fw.client()
    dmap = DebugMap.load(fw.map_path)
    poller = TargetLink(dmap, str(fw.link))
    rng = random.Random(SEED)
    kinds = set()
    for items in random_sets(dmap, rng):  # halted: plain reads, the console's values
        snap = poller.read_snapshot(client, items)
        assert snap.halted and snap.consistency == "halted"
        assert snap.values == dict(zip([it.id for it in items],
                                       client.read([(it.id, it.type, it.count) for it in items])))
    client.run()
    seqs = []
    for items in random_sets(dmap, rng):  # running: one instant when it fits
        snap = poller.read_snapshot(client, items)
        assert not snap.halted, snap
        assert set(snap.values) == {it.id for it in items}
        expected = "instant" if fits_one_transaction(client, items) else "split"
        assert snap.consistency == expected, (len(items), snap.consistency)
        kinds.add(snap.consistency)
        seqs.append(snap.seq)
        assert snap.round_trips >= (4 if expected == "instant" else 2) and snap.wire_bytes > 0
        # a wrong guess of the state (the last snapshot's) is corrected by the flags read after
        guessed = poller.read_snapshot(client, items, halted=True)
        assert not guessed.halted and guessed.consistency == "split"
    assert seqs == sorted(seqs) and len(set(seqs)) == len(seqs)
    client.halt()
    fw.wait_halted(client)
    small = dmap.items[:3]
    # halted at an instant: the commit applies at once (no wait), then the flags say halted: read again
    at_instant = poller.read_snapshot(client, small, halted=False)
    assert at_instant.halted and at_instant.consistency == "halted"
    assert at_instant.values == poller.read_snapshot(client, small).values
    client.step("task")  # halted inside an activation: a commit waits for the next instant
    assert fw.wait_halted(client).location.kind == K.P_TASK
    guessed = poller.read_snapshot(client, small, halted=False)  # never applied: aborted, read as halted
    assert guessed.halted and guessed.consistency == "halted"
    assert guessed.values == poller.read_snapshot(client, small).values
    assert client.flags().status & K.S_TX_OPEN == 0
    if model == "many_vars":
        assert kinds == {"instant", "split"}
        tx_max = client.hello_info.tx_max
        assert not fits_one_transaction(client, dmap.items[:tx_max + 1])
        assert fits_one_transaction(client, dmap.items[:tx_max])


def test_the_elements_are_the_maps_points_and_items(builds):
    exe = builds["pneumatic_cylinder"]
    dmap = DebugMap.load(exe.parent / "debug_map.json")
    els = elements(dmap, element_ids(render_svg(ROOT / "examples" / "pneumatic_cylinder.elab")))
    points = {(p.kind, p.a, p.b) for p in dmap.points()}
    for el, info in els.items():
        assert info["point"] is None or tuple(info["point"]) in points, el
        assert all(i in dmap.by_id for i in info["items"]), el
    # every step, transition and actor of the map can take a breakpoint by a click
    clickable = {tuple(info["point"]) for info in els.values() if info["point"]}
    assert {(p.kind, p.a, p.b) for p in dmap.points() if p.kind in (K.P_STEP, K.P_TRANSITION, K.P_ACTOR)} <= clickable
    assert els["step:Cylinder.Extending"]["location"] == "examples/pneumatic_cylinder.elab:44"
    assert els["edge:PositionControl/pid.y->drive"]["items"] == [dmap.by_name["drive"].id]
    assert els["edge:PositionControl/position.value->pos.x"]["items"] == [dmap.by_name["position.value"].id]
    assert els["device:end_out"]["items"] == [dmap.by_name["end_out.level"].id]
    assert "edge:PositionControl/pos.y->pid.measured" not in els  # between two actors: no item holds it
    # the chart's last fired transition is polled with its steps and transitions, each transition knows its id
    fired = dmap.by_name["Cylinder.fired"].id
    assert els["step:Cylinder.Fault"]["fired_item"] == fired
    assert [(els[f"transition:Cylinder.{t['id']}"]["fired_item"], els[f"transition:Cylinder.{t['id']}"]["transition"])
            for t in dmap.charts[0]["transitions"]] == [(fired, t["id"]) for t in dmap.charts[0]["transitions"]]


def test_targets_as_the_console_takes_them():
    assert target_url("tcp:127.0.0.1:5000") == "socket://127.0.0.1:5000"
    assert target_url("/dev/ttyUSB0") == "/dev/ttyUSB0"
    assert target_url("socket://h:1") == "socket://h:1"


def test_the_guards_hold_where_the_firmware_takes_their_transitions(builds, firmware):
    """With a breakpoint on every transition of pneumatic_cylinder (its own
    stimulus, virtual time), each halt is a transition the firmware found
    enabled: the guard evaluated on the snapshot read there holds, and the
    other guards out of the halted step are whatever they are."""
    from easylab.host_tools.debug_web.guards import GuardValues

    fw = firmware(builds["pneumatic_cylinder"], "--stimulus", str(ROOT / "examples" / "pneumatic_cylinder.stimulus.csv"))
    client = fw.client()
    dmap = DebugMap.load(fw.map_path)
    guards = GuardValues.of_model(ROOT / "examples" / "pneumatic_cylinder.elab", dmap)
    assert guards is not None and len(guards.guards) == 7
    poller = TargetLink(dmap, str(fw.link), guards=guards,
                        elements={el: {"point": [K.P_TRANSITION, 0, int(el.rsplit(".", 1)[1])]} for el in guards.guards})
    needed = sorted({i for el in guards.guards for i in guards.needs(el)})
    items = [dmap.by_id[i] for i in needed]
    verified = set()
    for f in transition_halts(client, dmap.charts[0]["transitions"], timeout=2.0):  # the stimulus's cycles
        snap = poller.read_snapshot(client, items)
        element = f"transition:Cylinder.{f.location.b}"
        assert snap.element == element and snap.guards[element] is True, (element, snap.values, snap.guards)
        verified.add(element)
    assert len(verified) >= 5, verified  # the cycle's four transitions, and a timeout's
    # a guard is not evaluated without every item it reads
    client.halt()
    fw.wait_halted(client)
    assert "transition:Cylinder.1" not in poller.read_snapshot(client, items[:1]).guards


class _HaltsBeforeTheFlags:
    """The firmware's own client, except that the first GET_FLAGS after the
    reads comes only once the program has run on a few instants and halted:
    the race of a breakpoint reached between a refresh's reads and its
    flags, made certain."""

    def __init__(self, client, wait_halted):
        self._client, self._wait_halted, self.raced = client, wait_halted, False

    def __getattr__(self, name):
        return getattr(self._client, name)

    def flags(self):
        if not self.raced:
            self.raced = True
            time.sleep(0.08)  # eight 10 ms instants run on after the reads
            self._client.halt()
            self._wait_halted(self._client)
        return self._client.flags()


@pytest.mark.parametrize("fits", [True, False])
def test_a_program_that_halts_after_the_reads_gives_the_halted_values(fits, many_vars, firmware):
    fw = firmware(many_vars, halt=True)
    client = fw.client()
    dmap = DebugMap.load(fw.map_path)
    poller = TargetLink(dmap, str(fw.link))
    counting = dmap.by_name["v0"]
    items = [counting] + ([] if fits else [it for it in dmap.items if it is not counting])
    assert fits_one_transaction(client, items) == fits
    client.run()
    deadline = time.monotonic() + 5
    while client.read([(counting.id, counting.type, 1)])[0] <= 3:  # v0 counting
        assert time.monotonic() < deadline, "v0 does not count"
        time.sleep(0.01)
    racing = _HaltsBeforeTheFlags(client, fw.wait_halted)
    snap = poller.read_snapshot(racing, items, halted=False)
    assert racing.raced and snap.halted and snap.consistency == "halted", snap
    assert snap.values == poller.read_snapshot(client, items).values  # the state it halted in, not before
