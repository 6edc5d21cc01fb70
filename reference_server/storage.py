"""The platform's "hard disk": a data directory with the stored documents and the start pose.

Rules:
- File names are fixed, as in the original's start-up log (spec/datadir.py, erratum E-CMD-008).
- ``save`` is atomic: the data go to a temporary file in the same directory, which is flushed and fsync'ed,
  then renamed over the target with ``os.replace``, then the directory is fsync'ed. A crash at any instant
  leaves the old file or the new one, never a torn one. Temporary files a crash left behind are removed
  when the storage is opened.
- Only bytes cross this module; parsing and validation belong to spec.documents.
"""

from __future__ import annotations

import contextlib
import logging
import math
import os
import tempfile
from dataclasses import dataclass
from pathlib import Path

from pltf.fixtures import DIR as FIXTURES_DIR
from pltf.fixtures import seed_data_dir
from pltf.spec.datadir import FILES, START_POSE_FILE
from pltf.spec.documents import DocumentKind

log = logging.getLogger("pltf.server")

REPO_FIXTURES = FIXTURES_DIR

_TMP_SUFFIX = ".tmp"


class StorageError(Exception):
    """A file of the data dir is missing, unreadable or malformed (one-line message)."""


@dataclass(frozen=True)
class StartPose:
    """StartupPosition.dat: x, y in mm, angle in rad (the original logs "x:0 y:0 a:1.204")."""

    x: float
    y: float
    angle: float


class Storage:
    def __init__(self, root: Path | str) -> None:
        self.root = Path(root)
        self.root.mkdir(parents=True, exist_ok=True)
        self._remove_stale_temporaries()

    def path(self, kind: DocumentKind) -> Path:
        return self.root / FILES[kind]

    def is_empty(self) -> bool:
        return not any(self.root.iterdir())

    def read(self, kind: DocumentKind) -> bytes:
        path = self.path(kind)
        try:
            return path.read_bytes()
        except FileNotFoundError:
            raise StorageError(f"{path}: no such file") from None
        except OSError as exc:
            raise StorageError(f"{path}: {exc.strerror}") from None

    def save(self, kind: DocumentKind, data: bytes) -> Path:
        path = self.path(kind)
        try:
            atomic_write(path, data)
        except OSError as exc:
            raise StorageError(f"{path}: {exc.strerror or exc}") from None
        return path

    def read_start_pose(self) -> StartPose:
        """One line "x y angle" (mm, mm, rad); '#' starts a comment."""
        path = self.root / START_POSE_FILE
        try:
            text = path.read_text(encoding="latin-1")
        except FileNotFoundError:
            raise StorageError(f"{path}: no such file") from None
        except OSError as exc:
            raise StorageError(f"{path}: {exc.strerror}") from None
        lines = [ln.split("#", 1)[0].strip() for ln in text.splitlines()]
        lines = [ln for ln in lines if ln]
        if len(lines) != 1:
            raise StorageError(f"{path}: expected one line 'x y angle', found {len(lines)}")
        try:
            x, y, angle = (float(v) for v in lines[0].split())
        except ValueError:
            raise StorageError(f"{path}: expected three numbers 'x y angle', got {lines[0]!r}") from None
        if not all(math.isfinite(v) for v in (x, y, angle)):
            raise StorageError(f"{path}: numbers must be finite")
        return StartPose(x, y, angle)

    def seed_from_fixtures(self, fixtures: Path = REPO_FIXTURES) -> list[Path]:
        """Fill an empty data dir from the repository's fixtures (office floor, roadmap, program, pose)."""
        return seed_data_dir(self.root, fixtures)

    def _remove_stale_temporaries(self) -> None:
        for rel in FILES.values():
            folder = (self.root / rel).parent
            if folder.is_dir():
                for tmp in folder.glob(f".*{_TMP_SUFFIX}"):
                    log.warning("removing %s left by an interrupted save", tmp)
                    with contextlib.suppress(OSError):
                        tmp.unlink()


def atomic_write(path: Path, data: bytes) -> None:
    """Replace ``path`` with ``data`` so that a crash leaves either the old or the new content."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp_name = tempfile.mkstemp(prefix=f".{path.name}.", suffix=_TMP_SUFFIX, dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp_name, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp_name)
        raise
    fsync_dir(path.parent)


def fsync_dir(folder: Path) -> None:
    """Make a rename in ``folder`` durable (POSIX; a no-op where directories cannot be opened)."""
    try:
        dir_fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(dir_fd)
    except OSError:
        pass
    finally:
        os.close(dir_fd)
