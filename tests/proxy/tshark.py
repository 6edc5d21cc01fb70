"""Run the real tshark with the generated dissector and read what it prints (PDML), for the dissector's tests."""

from __future__ import annotations

import json
import shutil
import subprocess
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest

from pltf.proxy.dissector import OUTPUT, field_abbr
from pltf.spec.model import Direction, FieldDef, telegram_def


def tshark_path() -> str:
    path = shutil.which("tshark")
    if path is None:
        pytest.fail("tshark is not installed: `make tshark` (Debian package tshark) installs it")
    return path


def run_tshark(pcapng: Path, *extra: str, dissector: Path = OUTPUT) -> ET.Element:
    proc = subprocess.run(
        [tshark_path(), "-X", f"lua_script:{dissector}", "-r", str(pcapng), "-T", "pdml", *extra],
        capture_output=True,
        timeout=600,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr.decode(errors="replace")[-2000:]
    lua_errors = [line for line in proc.stderr.decode(errors="replace").splitlines() if "Lua" in line]
    assert not lua_errors, lua_errors
    in_tree = [line for line in proc.stdout.decode(errors="replace").splitlines() if "Lua Error" in line]
    assert not in_tree, in_tree[:3]
    return ET.fromstring(proc.stdout)


@dataclass
class Shown:
    """One telegram as tshark shows it: its label and its fields in order (name, show, showname)."""

    packet: int
    label: str
    fields: list[tuple[str, str, str]] = field(default_factory=list)

    def values(self, name: str) -> list[str]:
        return [show for n, show, _ in self.fields if n == name]

    @property
    def experts(self) -> list[str]:
        return [show for n, show, _ in self.fields if n == "_ws.expert.message"]


def telegrams(root: ET.Element) -> list[Shown]:
    out = []
    for number, packet in enumerate(root.iter("packet"), 1):
        for proto in packet.findall("proto"):
            if proto.get("name") != "pltf":
                continue
            shown = Shown(number, proto.get("showname", ""))
            for f in proto.iter("field"):
                shown.fields.append((f.get("name", ""), f.get("show", ""), f.get("showname", "")))
            out.append(shown)
    return out


Flat = list[tuple[str, str, Any]]  # (field name, wire type, value)


def _flatten(fields: tuple[FieldDef, ...], values: dict[str, Any], prefix: str, out: Flat) -> None:
    for f in fields:
        if f.const is not None:
            continue
        value = values[f.name]
        if f.is_group:
            for item in value:
                _flatten(f.fields, item, f"{prefix}{f.name}.", out)
        elif f.repeat:
            out.extend((prefix + f.name, f.type, v) for v in value)
        else:
            out.append((prefix + f.name, f.type, value))


def expected(direction: Direction, decoded: dict[str, Any]) -> list[tuple[str, str, Any]]:
    """What `pltf decode` printed, as (field name, wire type, value) in wire order."""
    tdef = telegram_def(decoded["telegram"])
    layout = tdef.layout(direction) if tdef.layout_known else None
    out: list[tuple[str, str, Any]] = []
    if layout is None:
        out.append((field_abbr(direction, tdef.name, "payload"), "OPAQUE", decoded["fields"]["payload"]))
    else:
        _flatten(layout, decoded["fields"], field_abbr(direction, tdef.name, ""), out)
    return out


def shown_value(kind: str, show: str, showname: str) -> Any:
    """The value tshark printed: numbers from ``show``; doubles from the label (PDML's ``show`` of a double has
    only 15 digits); strings JSON-escaped by the dissector; opaque payloads as hex."""
    if kind == "DOUBLE":
        return float(showname.split(": ", 1)[1].split(" ", maxsplit=1)[0])
    if kind in ("STRING", "XML"):
        return json.loads('"' + show + '"')
    if kind == "OPAQUE":
        return show.replace(":", "")
    return int(show)
