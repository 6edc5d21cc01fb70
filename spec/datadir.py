"""The platform's data directory (its "hard disk"): the fixed file of each stored document and of the start pose.

Rules (erratum E-CMD-008): CMD_LOAD_*/CMD_SAVE_* carry no file name, so the files are named as in the original's
start-up log at the top of the guide ("load map: Platform/Map/PltfMap.map", "load roadmap:
Platform/Roadmap/PltfRoadmap.rm", "init pose read from StartupPosition.dat"); the program file follows the same
pattern. Paths are relative to the data directory. Every implementation that keeps a disk uses them (the
reference server's storage, the Go emulator's --data-dir, the fixtures that seed a fresh one).
"""

from __future__ import annotations

from pltf.spec.documents import DocumentKind

FILES: dict[DocumentKind, str] = {
    DocumentKind.MAP: "Map/PltfMap.map",
    DocumentKind.ROADMAP: "Roadmap/PltfRoadmap.rm",
    DocumentKind.PROGRAM: "Program/PltfProgram.xml",
}
START_POSE_FILE = "StartupPosition.dat"
