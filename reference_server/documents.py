"""The active map, roadmap and program (guide 6.3 CMD_SET/GET/LOAD/SAVE_MAP, _ROADMAP, _PROGRAM).

Rules:
- A document becomes active only after spec.documents validated it against its schema; a refused one
  (``DocumentError``, ``StorageError``) leaves the active one in place.
- The bytes are kept exactly as received, so GET returns what SET sent and SAVE writes it unchanged.
- The wire carries XML as Latin-1 text (erratum E-WIRE-003): ``from_wire``/``to_wire`` convert losslessly.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pltf.reference_server.storage import Storage, StorageError
from pltf.reference_server.tasks.program import compile_program
from pltf.spec.documents import DocumentKind, validate_document


@dataclass(frozen=True)
class Document:
    kind: DocumentKind
    name: str
    data: bytes
    tree: Any  # the validated lxml ElementTree


class NoActiveDocument(StorageError):
    """SAVE without an active document of that kind."""


def from_wire(text: str) -> bytes:
    return text.encode("latin-1")


def to_wire(data: bytes) -> str:
    return data.decode("latin-1")


class Documents:
    def __init__(self, storage: Storage) -> None:
        self.storage = storage
        self._active: dict[DocumentKind, Document] = {}

    def get(self, kind: DocumentKind) -> Document | None:
        return self._active.get(kind)

    def set(self, kind: DocumentKind, name: str, data: bytes) -> Document:
        """Validate and activate; DocumentError leaves the active document unchanged."""
        tree = validate_document(kind, data)
        if kind is DocumentKind.PROGRAM:
            compile_program(tree)  # erratum E-TASK-016: a program that cannot run is refused like an invalid one
        doc = Document(kind, name, data, tree)
        self._active[kind] = doc
        return doc

    def load(self, kind: DocumentKind) -> Document:
        """Read the stored file and activate it; StorageError or DocumentError change nothing."""
        return self.set(kind, self.storage.path(kind).name, self.storage.read(kind))

    def save(self, kind: DocumentKind) -> Path:
        doc = self._active.get(kind)
        if doc is None:
            raise NoActiveDocument(f"no active {kind.value} to save")
        return self.storage.save(kind, doc.data)
