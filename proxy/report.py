"""What ``pltf replay`` prints and writes: the differences grouped by telegram, and a JUnit XML report.

Rules: one block per telegram (replies, then ``(connection)`` for connection behaviour), in the order their
first difference happened; each line says where (connection, seconds into the recording, the request) and what
(the field, the recorded value, the replayed value). Long lists are cut at ``SHOWN`` lines per telegram, with
the count of the rest. The JUnit report has one test case per reply telegram replayed (failed when it differs)
and one for the connections.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

from pltf.proxy.replay import Difference, group

SHOWN = 20


def line(d: Difference) -> str:
    return (
        f"  #{d.conn} :{d.port} {d.at:8.3f} s  {d.request}\n"
        f"      {d.path}: recorded {d.recorded}, replayed {d.replayed}"
    )


def render(differences: list[Difference], counts: dict[str, int]) -> str:
    head = (
        f"replayed {counts['sent']} of {counts['requests']} requests on {counts['connections']} connections "
        f"({counts['replies compared']} replies compared, {counts['waits']} waits)"
    )
    if not differences:
        return f"{head}: no difference\n"
    blocks = [head + ":"]
    for name, diffs in group(differences).items():
        blocks.append(f"{name}: {len(diffs)} difference{'s' if len(diffs) != 1 else ''}")
        blocks += [line(d) for d in diffs[:SHOWN]]
        if len(diffs) > SHOWN:
            blocks.append(f"  ... and {len(diffs) - SHOWN} more")
    total = len(differences)
    blocks.append(f"{total} difference{'s' if total != 1 else ''} in {len(group(differences))} telegram(s)")
    return "\n".join(blocks) + "\n"


def write_junit(path: Path, differences: list[Difference], telegrams: list[str], seconds: float) -> None:
    """``telegrams``: the reply telegrams the recording has, in the order they first came."""
    by_name = group(differences)
    names = list(telegrams)
    names += [n for n in by_name if n not in names and n != "(connection)"]
    names.append("(connection)")
    failures = sum(1 for n in names if n in by_name)
    suites = ET.Element(
        "testsuites", name="pltf replay", tests=str(len(names)), failures=str(failures), time=f"{seconds:.3f}"
    )
    suite = ET.SubElement(suites, "testsuite", name="replay", tests=str(len(names)), failures=str(failures))
    for name in names:
        case = ET.SubElement(suite, "testcase", classname="replay", name=name)
        diffs = by_name.get(name, [])
        if diffs:
            fail = ET.SubElement(case, "failure", message=f"{len(diffs)} difference(s)")
            fail.text = "\n".join(line(d) for d in diffs)
    ET.indent(suites)
    path.write_text(ET.tostring(suites, encoding="unicode", xml_declaration=True) + "\n", encoding="utf-8")
