"""The data dir: fixed file names, atomic save, start pose, seeding."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from pltf.reference_server import storage as storage_mod
from pltf.reference_server.storage import FILES, START_POSE_FILE, Storage, StorageError, atomic_write
from pltf.spec.documents import DocumentKind, validate_document


def test_seed_from_fixtures_fills_an_empty_dir_only(tmp_path: Path) -> None:
    store = Storage(tmp_path / "d")
    written = store.seed_from_fixtures()
    assert {p.relative_to(store.root).as_posix() for p in written} == {*FILES.values(), START_POSE_FILE}
    for kind in FILES:
        validate_document(kind, store.read(kind))
    assert store.seed_from_fixtures() == []  # not empty any more


def test_file_names_follow_the_original_log(tmp_path: Path) -> None:
    store = Storage(tmp_path)
    assert store.path(DocumentKind.MAP) == tmp_path / "Map" / "PltfMap.map"
    assert store.path(DocumentKind.ROADMAP) == tmp_path / "Roadmap" / "PltfRoadmap.rm"
    assert store.path(DocumentKind.PROGRAM) == tmp_path / "Program" / "PltfProgram.xml"


def test_save_replaces_and_leaves_no_temporary(tmp_path: Path) -> None:
    store = Storage(tmp_path)
    store.save(DocumentKind.MAP, b"old")
    store.save(DocumentKind.MAP, b"new")
    assert store.read(DocumentKind.MAP) == b"new"
    assert sorted(p.name for p in (tmp_path / "Map").iterdir()) == ["PltfMap.map"]


def test_a_failed_save_keeps_the_old_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    store = Storage(tmp_path)
    store.save(DocumentKind.MAP, b"old")

    def broken_replace(src: str, dst: str) -> None:
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(storage_mod.os, "replace", broken_replace)
    with pytest.raises(StorageError, match="No space left"):
        store.save(DocumentKind.MAP, b"new")
    assert store.read(DocumentKind.MAP) == b"old"
    assert sorted(p.name for p in (tmp_path / "Map").iterdir()) == ["PltfMap.map"]


def test_a_failed_fsync_keeps_the_old_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    target = tmp_path / "f"
    atomic_write(target, b"old")
    calls: list[int] = []

    def broken_fsync(fd: int) -> None:
        calls.append(fd)
        raise OSError(5, "Input/output error")

    monkeypatch.setattr(storage_mod.os, "fsync", broken_fsync)
    with pytest.raises(OSError):
        atomic_write(target, b"new")
    assert calls
    assert target.read_bytes() == b"old"
    assert [p.name for p in tmp_path.iterdir()] == ["f"]


def test_save_order_is_write_fsync_replace_fsync_dir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    events: list[str] = []
    real_fsync, real_replace = os.fsync, os.replace

    def fsync(fd: int) -> None:
        events.append("fsync-dir" if Path(f"/proc/self/fd/{fd}").resolve().is_dir() else "fsync-file")
        real_fsync(fd)

    def replace(src: str, dst: str) -> None:
        assert Path(src).parent == Path(dst).parent, "the temporary file must be in the target's directory"
        events.append("replace")
        real_replace(src, dst)

    monkeypatch.setattr(storage_mod.os, "fsync", fsync)
    monkeypatch.setattr(storage_mod.os, "replace", replace)
    atomic_write(tmp_path / "x", b"data")
    assert events == ["fsync-file", "replace", "fsync-dir"]


def test_stale_temporaries_are_removed_on_open(tmp_path: Path) -> None:
    (tmp_path / "Map").mkdir()
    stale = tmp_path / "Map" / ".PltfMap.map.abc123.tmp"
    stale.write_bytes(b"<map")
    Storage(tmp_path)
    assert not stale.exists()


def test_missing_file_is_a_storage_error(tmp_path: Path) -> None:
    with pytest.raises(StorageError, match="no such file"):
        Storage(tmp_path).read(DocumentKind.ROADMAP)


@pytest.mark.parametrize(
    ("text", "pose"),
    [
        ("2000 10000 0.0\n", (2000.0, 10000.0, 0.0)),
        ("# comment\n  -1.5 2 1.204  # trailing\n\n", (-1.5, 2.0, 1.204)),
    ],
)
def test_start_pose(tmp_path: Path, text: str, pose: tuple[float, float, float]) -> None:
    (tmp_path / START_POSE_FILE).write_text(text)
    p = Storage(tmp_path).read_start_pose()
    assert (p.x, p.y, p.angle) == pose


@pytest.mark.parametrize("text", ["", "1 2\n", "1 2 3\n4 5 6\n", "a b c\n", "1 2 nan\n"])
def test_bad_start_pose(tmp_path: Path, text: str) -> None:
    (tmp_path / START_POSE_FILE).write_text(text)
    with pytest.raises(StorageError):
        Storage(tmp_path).read_start_pose()
