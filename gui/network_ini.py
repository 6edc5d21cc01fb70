"""The known platform addresses: guide 5.2 "extend the file 'PltfGUI\\res\\inifiles.Network.ini' with the
missing server".

The guide does not show the file's content; ours (erratum E-GUI-001) is an INI file with one section
``[Network]`` whose values are
``HOST:PORT`` (the keys are free names)::

    [Network]
    lab = 192.168.0.10:10000
    simulator = 127.0.0.1:10000

A missing file is an empty list; an unreadable or malformed one is reported in one line and treated as empty.
"""

from __future__ import annotations

import configparser
import logging
import os
from pathlib import Path

from pltf.gui.link import parse_target

log = logging.getLogger("pltf.gui")
SECTION = "Network"


def default_path() -> Path:
    base = os.environ.get("XDG_CONFIG_HOME") or str(Path.home() / ".config")
    return Path(base) / "pltf" / "Network.ini"


class NetworkIni:
    def __init__(self, path: Path) -> None:
        self.path = path

    def _read(self) -> configparser.ConfigParser:
        parser = configparser.ConfigParser(interpolation=None)
        try:
            parser.read(self.path, encoding="utf-8")
        except (OSError, configparser.Error, UnicodeDecodeError) as exc:
            log.warning("%s: not read (%s)", self.path, str(exc).splitlines()[0])
        return parser

    def targets(self) -> list[str]:
        parser = self._read()
        if not parser.has_section(SECTION):
            return []
        out: list[str] = []
        for _, value in parser.items(SECTION):
            try:
                parse_target(value)
            except ValueError:
                log.warning("%s: ignored %r (not HOST:PORT)", self.path, value)
                continue
            if value.strip() not in out:
                out.append(value.strip())
        return out

    def add(self, target: str) -> None:
        """Add ``HOST:PORT`` (ValueError if malformed); a known one is left alone."""
        parse_target(target)
        target = target.strip()
        parser = self._read()
        if not parser.has_section(SECTION):
            parser.add_section(SECTION)
        if target in (v.strip() for _, v in parser.items(SECTION)):
            return
        n = len(parser.items(SECTION)) + 1
        while parser.has_option(SECTION, f"server{n}"):
            n += 1
        parser.set(SECTION, f"server{n}", target)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        with self.path.open("w", encoding="utf-8") as fh:
            parser.write(fh)
