"""The shards' rules without Ray (reference_server/fleet/shards.py): the plan, the exchange's lag and stall, and two
shards of the head-on scenario stepped in one thread - what ``pltf serve --fleet FILE --ray`` runs on each node.
Default tier: no cluster, no sockets."""

from __future__ import annotations

import threading
import time
from pathlib import Path
from typing import Any

import pytest
import yaml

from pltf.reference_server import hardware_link
from pltf.reference_server.fleet import config
from pltf.reference_server.fleet.bodies import Bodies
from pltf.reference_server.fleet.fleet import Fleet, FleetPlatform
from pltf.reference_server.fleet.shards import Exchange, ShardWorld, Snapshot, plan
from pltf.reference_server.storage import Storage
from pltf.reference_server.tasks.local import factory as program_factory
from pltf.reference_server.world.model import factory as world_factory
from pltf.spec.codec import REQUESTS as R
from pltf.spec.codec import decode_frame, encode
from tests.reference_server.test_fleet import FRONT, HEAD_ON, MODE_VEL

DT = 0.02


def spec(text: str) -> config.FleetSpec:
    return config.parse(yaml.safe_load(text))


def snap(shard: int, tick: int, x: float = 0.0) -> Snapshot:
    return Snapshot(shard, tick, 0.0, (shard,), ((x, 0.0, 0.0),), ((225.0, -425.0, 270.0),), (True,))


def test_plan_places_named_nodes_and_the_rest_round_robin() -> None:
    doc = yaml.safe_load(HEAD_ON)
    doc["platforms"][1]["node"] = 2
    doc["platforms"].append({"name": "charlie", "ports": [0, 0]})
    doc["platforms"].append({"name": "delta", "ports": [0, 0], "seed": 7})
    shards = {p.shard: p for p in plan(config.parse(doc), 3, seed=100)}
    # alpha, charlie and delta have no node: 0, 1, 2 in the file's order; seeds 100 + the fleet index
    names = {p.name: (s, p.seed) for s, sp in shards.items() for p in sp.platforms}
    assert names == {"alpha": (0, 100), "bravo": (2, 101), "charlie": (1, 102), "delta": (2, 7)}
    assert shards[2].indices == (1, 3) and shards[2].owners == {0: (0,), 1: (2,)}
    assert all(sp.total == 4 for sp in shards.values())


def test_plan_refuses_a_node_the_cluster_does_not_have() -> None:
    doc = yaml.safe_load(HEAD_ON)
    doc["platforms"][1]["node"] = 2
    with pytest.raises(config.FleetError, match=r"'bravo': node 2, but the Ray cluster has 2 \(0..1\)"):
        plan(config.parse(doc), 2, seed=0)


def test_node_must_be_an_index() -> None:
    doc = yaml.safe_load(HEAD_ON)
    doc["platforms"][0]["node"] = "head"
    with pytest.raises(config.FleetError, match="'node' must be a node index"):
        config.parse(doc)


def test_exchange_gives_the_peers_tick_k_minus_lag_and_waits_for_it() -> None:
    ex = Exchange([1], time.monotonic, lag=2, stall=5.0)
    for t in (0, 1, 2, 3):  # the peer is ahead of us: its newest snapshot is not the one tick 3 needs
        ex.put(snap(1, t, x=float(t)))
    snaps, gone = ex.view(3)
    assert [s.tick for s in snaps] == [1] and not gone
    threading.Timer(0.3, ex.put, (snap(1, 4),)).start()
    t0 = time.monotonic()
    snaps, _ = ex.view(6)  # needs tick 4, not there yet: waits for it
    assert time.monotonic() - t0 >= 0.25 and [s.tick for s in snaps] == [4]
    assert ex.stats.late == 0 and ex.stats.waits == 1


def test_a_late_peer_is_waited_for_once_then_skipped_until_it_catches_up() -> None:
    ex = Exchange([1], time.monotonic, lag=1, stall=1.0)
    ex.put(snap(1, 0))
    t0 = time.monotonic()
    snaps, _ = ex.view(5)  # tick 4 never comes: one stall, then on with the newest
    assert 0.9 < time.monotonic() - t0 < 10.0 and [s.tick for s in snaps] == [0] and ex.stats.late == 1
    t0 = time.monotonic()
    ex.view(6)  # a wait again would take the stall's 1 s; half of it leaves a loaded machine room
    assert time.monotonic() - t0 < 0.5, "waited again for a late peer"
    ex.put(snap(1, 6))
    assert [s.tick for s in ex.view(7)[0]] == [6]  # caught up: lockstep again
    ex.drop(1)
    snaps, gone = ex.view(20)
    assert snaps == [] and gone == {1}


def _shard(tmp: Path, spec_: config.FleetSpec, mine: list[int]) -> Fleet:
    platforms = []
    for k in mine:
        p = spec_.platforms[k]
        storage = Storage(tmp / p.name)
        storage.seed_from_fixtures()
        seed = k + 1
        platforms.append(
            FleetPlatform(
                storage,
                seed=seed,
                motion=world_factory(seed),
                program=program_factory,
                hardware=hardware_link.factory(),
            )
        )
    sub = config.FleetSpec(tuple(spec_.platforms[k] for k in mine))
    return Fleet(sub, platforms, bodies=Bodies(len(spec_)), indices=mine)


def _step(worlds: list[Any], k: int) -> None:
    for w in worlds:
        w.tick(k * DT)


def _bring_up(worlds: list[Any], members: list[Any]) -> int:
    """Both initialised (the boards' self test), velocity mode, Running; the tick reached."""
    for m in members:
        for t in (R.CMD_CONNECT_TO_PLTF(), R.CMD_INIT_PLTF()):
            m.platform.handle(t, 0.0)
    k = 0
    while k < 200 and any(m.platform.chart.state.name != "READY" for m in members):
        k += 1
        _step(worlds, k)
    for m in members:
        for t in (R.CMD_SET_MODE(mode=MODE_VEL), R.CMD_START()):
            m.platform.handle(t, k * DT)
    return k


class _OneWorld:
    """The whole fleet in one process (what ``pltf serve --fleet`` ticks), stepped like a shard."""

    def __init__(self, fleet: Fleet) -> None:
        self.fleet = fleet

    def tick(self, now: float) -> None:
        self.fleet.tick(now)


def _ask(members: list[Any], now: float) -> list[bytes]:
    """The bytes a client reads for GET_STATUS and GET_POSITION from each platform at ``now``."""
    out = []
    for m in members:
        for t in (R.CMD_GET_STATUS(), R.CMD_GET_POSITION()):
            outcome = m.platform.handle(t, now)
            out.append(outcome.frame if outcome.frame is not None else encode(outcome.reply))
    return out


def _drive(worlds: list[Any], members: list[Any], replies: list[bytes] | None = None) -> list[tuple[float, float]]:
    first = _bring_up(worlds, members)
    go = R.CMD_MOVE_VEL(vel_trans=400, vel_rot=0)
    xs = []
    for k in range(first + 1, first + 1 + 600):  # 12 s simulated: they meet after ~4 s
        if k % 5 == 0:
            for m in members:
                m.platform.handle(go, k * DT)
        if replies is not None and k % 25 == 0:
            replies += _ask(members, k * DT)
        _step(worlds, k)
        xs.append((members[0].world.truth[0], members[1].world.truth[0]))
    return xs


def _head_on_in_one_process(tmp: Path, replies: list[bytes] | None = None) -> list[tuple[float, float]]:
    fleet = _shard(tmp, spec(HEAD_ON), [0, 1])
    try:
        fleet.boot(0.0)
        return _drive([_OneWorld(fleet)], fleet.members, replies)
    finally:
        fleet.close()


def _head_on_in_two_shards(tmp: Path, lag: int = 1, replies: list[bytes] | None = None) -> list[tuple[float, float]]:
    """alpha in shard 0, bravo in shard 1, stepped in lockstep; alpha's and bravo's true x every tick."""
    s = spec(HEAD_ON)
    fleets = [_shard(tmp, s, [0]), _shard(tmp, s, [1])]
    exchanges = [Exchange([1], time.monotonic, lag, stall=1.0), Exchange([0], time.monotonic, lag, stall=1.0)]
    worlds = [
        ShardWorld(fleets[i], i, exchanges[i], {1 - i: (1 - i,)}, exchanges[1 - i].put_all, time.monotonic)
        for i in (0, 1)
    ]
    try:
        for f, w in zip(fleets, worlds, strict=True):
            f.boot(0.0)
            w.publish(0)
        xs = _drive(worlds, [f.members[0] for f in fleets], replies)
        assert exchanges[0].stats.late == 0 and exchanges[1].stats.late == 0
        return xs
    finally:
        for f in fleets:
            f.close()


@pytest.mark.parametrize("lag", [1, 3])
def test_two_shards_block_each_other_and_run_the_same_every_time(tmp_path: Path, lag: int) -> None:
    xs = _head_on_in_two_shards(tmp_path / "a", lag)
    assert xs[-1][0] > xs[0][0] + 500 and xs[-1][1] < xs[0][1] - 500, "they did not drive"
    gaps = [(xb - FRONT) - (xa + FRONT) for xa, xb in xs]
    assert min(gaps) > -40, "alpha's front passed bravo's"
    assert gaps[-1] < 900 and abs(gaps[-1] - gaps[-50]) < 1, "not held back in front of each other"
    again = _head_on_in_two_shards(tmp_path / "b", lag)
    assert again == xs  # deterministic: same seeds, same telegrams at the same ticks


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--ray", "auto"], "--ray needs --fleet"),
        (
            ["--fleet", "FILE", "--ray", "auto", "--shared-map"],
            "--shared-map hands a map on in one process: not with --ray, --processes",
        ),
        (["--fleet", "FILE", "--ray", "auto", "--ray-lag", "0"], "--ray-lag must be at least 1 (period)"),
    ],
)
def test_what_ray_refuses_is_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], argv: list[str], message: str
) -> None:
    from pltf.reference_server.cli import main

    (tmp_path / "fleet.yaml").write_text(HEAD_ON, encoding="utf-8")
    argv = [str(tmp_path / "fleet.yaml") if a == "FILE" else a for a in argv]
    assert main([*argv, "--data-dir", str(tmp_path / "data")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1] == f"python -m pltf.reference_server: error: {message}", err


# what may differ in bravo's replies: what its laser sees of alpha (one period, <= 8 mm, apart), and the
# localization's estimate that matches those scans (E-FLEET-004)
SEEN_OF_THE_OTHER = {"scan", "lines", "cov_axis_angle", "cov_x", "cov_y", "cov_xy", "x", "y", "angle"}


def _fields(frame: bytes) -> dict[str, Any]:
    t = decode_frame(frame, "reply")
    return {n: getattr(t, n) for n in dir(t) if n.islower() and not n.startswith("_") and not callable(getattr(t, n))}


def test_two_shards_answer_what_one_process_answers(tmp_path: Path) -> None:
    """The same telegrams at the same ticks, one process against two shards (lag 1). alpha, ticked first in one
    process, sees bravo's pose of the period before in both: every GET_STATUS and GET_POSITION reply the same
    bytes. bravo in one process sees alpha's move of the same period, in a shard that of the period before: its
    replies differ only in what it sees of alpha and in the estimate built on that, by less than a period's
    travel. The true trajectories are the same: both stop at the same tick, at the same place."""
    across: list[bytes] = []
    alone: list[bytes] = []
    sharded = _head_on_in_two_shards(tmp_path / "shards", replies=across)
    one = _head_on_in_one_process(tmp_path / "one", replies=alone)
    assert len(across) == len(alone) > 80
    alpha = [k for k in range(len(across)) if k % 4 < 2]  # _ask: alpha's status, position, bravo's status, position
    assert [k for k in alpha if across[k] != alone[k]] == []
    for k in range(len(across)):
        a, b = _fields(across[k]), _fields(alone[k])
        differ = {n for n in a if a[n] != b[n]}
        assert differ <= SEEN_OF_THE_OTHER, (k, differ)
        for n in {"x", "y"} & differ:
            assert abs(a[n] - b[n]) <= 10, (k, n, a[n], b[n])
        if "angle" in differ:
            assert abs(a["angle"] - b["angle"]) < 1e-3, (k, a["angle"], b["angle"])
    assert sharded == one
