"""The prefetch child: the stream it hands over is the scheduler's, knowledge reaches it, failures surface."""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from pltf.fuzz.case import Case
from pltf.fuzz.knowledge import Knowledge
from pltf.fuzz.prefetch import AHEAD, PIPE_SIZE, Prefetcher
from pltf.fuzz.safety import forbidden
from pltf.fuzz.schedule import Scheduler


class PoseEcho:
    """A scheduler whose case ``i`` carries ``i`` and the pose it knew when it drew it (and is ``size`` long)."""

    def __init__(self, size: int = 8, fail_at: int | None = None) -> None:
        self.kb, self.dropped, self.size, self.fail_at = Knowledge(), 0, size, fail_at

    def case(self, i: int) -> Case:
        if i == self.fail_at:
            raise ValueError(f"case {i} cannot be drawn")
        head = f"{i}:{self.kb.pose[0]}".encode()
        return Case(frames=(head.ljust(self.size, b"."),), origin="test", telegram="-")


@pytest.mark.parametrize("compiled", [False, True])
def test_the_windows_are_the_schedulers_stream_in_order(compiled: bool) -> None:
    """Drawn by the forked child (the Python stream), or where they are taken (the compiled core, pltf.fuzz.draw),
    across a block's end (schedule.BLOCK)."""
    sched = Scheduler(7, forbidden(allow_motion=False), Knowledge(), compiled=compiled)
    stream = Scheduler(7, forbidden(allow_motion=False), Knowledge(), compiled=compiled)
    expected = [stream.case(i).data for i in range(200, 328)]
    pre = Prefetcher(sched, 200, 32)
    try:
        got: list[bytes] = []
        firsts = []
        for _ in range(4):
            first, cases = pre.get()
            firsts.append(first)
            got += [c.data for c in cases]
        assert firsts == [200, 232, 264, 296]
        assert got == expected
        assert (pre.proc is None) == sched.compiled  # the forked child drew them, not a thread
    finally:
        pre.close()


def test_what_the_parent_learns_reaches_later_windows() -> None:
    sched = PoseEcho()
    pre = Prefetcher(sched, 0, 4)  # type: ignore[arg-type]
    try:
        pre.get()
        sched.kb.pose = (4321, 0, 0)
        sched.kb.version += 1
        deadline = time.monotonic() + 20
        while time.monotonic() < deadline:
            _, cases = pre.get()
            if all(c.data.startswith(f"{int(c.data.split(b':')[0])}:4321".encode()) for c in cases):
                break
        else:
            pytest.fail("the child never drew with the pose the parent learnt")
    finally:
        pre.close()


def test_a_window_larger_than_the_pipe_arrives_whole() -> None:
    sched = PoseEcho(size=PIPE_SIZE)
    pre = Prefetcher(sched, 0, 3)  # type: ignore[arg-type]
    try:
        for start in (0, 3):
            first, cases = pre.get()
            assert first == start
            assert [len(c.data) for c in cases] == [PIPE_SIZE] * 3
            assert [c.data.split(b":")[0] for c in cases] == [str(start + k).encode() for k in range(3)]
    finally:
        pre.close()


def test_a_failure_in_the_child_is_reported_with_its_traceback() -> None:
    pre = Prefetcher(PoseEcho(fail_at=5), 0, 4)  # type: ignore[arg-type]
    try:
        pre.get()
        with pytest.raises(RuntimeError, match="case 5 cannot be drawn"):
            pre.get()
    finally:
        pre.close()


def test_close_ends_the_child() -> None:
    pre = Prefetcher(PoseEcho(), 0, 4)  # type: ignore[arg-type]
    proc = pre.proc
    pre.get()
    pre.close()
    assert proc is not None and not proc.is_alive()


class Tally(PoseEcho):
    """A PoseEcho that writes each index it draws to a file (the child's draws, seen from the parent)."""

    def __init__(self, path: Path) -> None:
        super().__init__()
        self.path = path

    def case(self, i: int) -> Case:
        with self.path.open("a") as f:
            f.write(f"{i}\n")
        return super().case(i)


def test_the_child_draws_no_further_ahead_than_the_windows_the_campaign_has_not_taken(tmp_path: Path) -> None:
    drawn = tmp_path / "drawn"
    pre = Prefetcher(Tally(drawn), 0, 4)  # type: ignore[arg-type]
    try:
        for taken in (1, 2, 5):
            while pre.get()[0] < 4 * (taken - 1):
                pass
            time.sleep(0.3)  # time to draw many more windows of 4 tiny cases, were it not held back
            indices = [int(line) for line in drawn.read_text().split()]
            assert max(indices) < 4 * (taken + AHEAD), f"{taken} windows taken, drew up to case {max(indices)}"
    finally:
        pre.close()
