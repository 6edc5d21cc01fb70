"""Program documents -> ``model.Program`` (guide 6.5 Program, Task).

Rules:
- Validation against spec/schemas is spec.documents' job (``validate_document``); this module compiles a valid
  tree and adds the checks an XSD cannot make (E-TASK-016): every goto label and timeoutlabel names a label of
  the same task, label names are unique in their task, every onErrorTask names a task, random's min <= max.
  Any failure is a ``ProgramError`` (a ``DocumentError``) naming the line, so a caller refuses it exactly like
  a schema violation and the active program stays.
- Defaults of absent attributes are the schema's (E-XML-015): angles 0, Dn -1, flags false, no timeout.
"""

from __future__ import annotations

from collections.abc import Callable
from decimal import Decimal
from typing import Any

from pltf.reference_server.tasks import model as m
from pltf.spec.documents import DocumentError, DocumentKind, validate_document

_TRUE = frozenset({"true", "1"})


class ProgramError(DocumentError):
    """A schema-valid program that cannot run (unknown label or task, duplicate label, min > max)."""

    def __init__(self, reason: str, line: int | None) -> None:
        super().__init__(reason, kind=DocumentKind.PROGRAM, line=line)


def load_program(data: bytes) -> m.Program:
    """Validate ``data`` as a program document and compile it; DocumentError (or ProgramError) when refused."""
    return compile_program(validate_document(DocumentKind.PROGRAM, data))


def compile_program(tree: Any) -> m.Program:
    root = tree.getroot() if hasattr(tree, "getroot") else tree
    tasks = tuple(_task(el) for el in root.iterfind("task"))
    program = m.Program(tasks)
    for task in tasks:
        for cmd in task.commands:
            if isinstance(cmd, m.MoveTo) and cmd.on_error_task is not None and program.task(cmd.on_error_task) is None:
                raise ProgramError(f"task {task.title!r}: onErrorTask {cmd.on_error_task!r} names no task", cmd.line)
    return program


def _flag(el: Any, name: str) -> bool:
    return el.get(name, "false").strip() in _TRUE


def _num(text: str) -> float:
    return float(Decimal(text.strip()))  # xs:decimal: no exponent, '.' as point (E-XML-006)


def _opt_num(el: Any, name: str) -> float | None:
    text = el.get(name)
    return None if text is None else _num(text)


def _priority(text: str | None) -> int:
    try:
        return int((text or "").strip())
    except ValueError:
        return 0  # E-XML-022: a non-integer or absent priority is 0


def _task(el: Any) -> m.Task:
    commands: list[m.Command] = []
    labels: dict[str, int] = {}
    for child in el:
        if not isinstance(child.tag, str):
            continue  # comments, processing instructions
        cmd = _COMMANDS[child.tag](child)
        if isinstance(cmd, m.Label):
            if cmd.name in labels:
                raise ProgramError(f"task {el.get('name', '')!r}: label {cmd.name!r} defined twice", cmd.line)
            labels[cmd.name] = len(commands)
        commands.append(cmd)
    task = m.Task(
        name=el.get("name", "").strip(),
        id=el.get("id", ""),
        priority=_priority(el.get("priority")),
        commands=tuple(commands),
        labels=labels,
        line=el.sourceline or 0,
    )
    for cmd in commands:
        target = cmd.label if isinstance(cmd, m.Goto) else cmd.timeout_label if isinstance(cmd, m.Wait) else None
        if target is not None and target not in labels:
            raise ProgramError(f"task {task.title!r}: no label {target!r} in this task", cmd.line)
    return task


# ---- one compiler per element of the task
def _ioevent(el: Any) -> m.Command:
    out = el.find("digitalout")
    return m.DigitalOut(el.sourceline, tuple(int(out.get(f"D{n}", "-1")) for n in range(1, 13)))


def _goto(el: Any) -> m.Command:
    return m.Goto(el.sourceline, el.get("label"), (el.get("condition") or "true").strip())


def _label(el: Any) -> m.Command:
    return m.Label(el.sourceline, el.get("name"))


def _load(el: Any) -> m.Command:
    return m.Load(el.sourceline, el.get("map"), el.get("roadmap"))


def _log(el: Any) -> m.Command:
    return m.Log(el.sourceline, el.get("type", "info"), el.get("message"))


def _motion(el: Any) -> m.Command:
    target = el.find("settarget")
    moveto = el.find("moveto")
    if _flag(el, "stop"):  # E-TASK-007: stop="1" wins over a target given beside it
        return m.Stop(el.sourceline)
    if target is not None:
        coord = target.find("coord")
        if coord is not None:
            return m.MoveCoord(el.sourceline, _num(coord.get("x")), _num(coord.get("y")), _num(coord.get("angle", "0")))
        return m.MoveStation(el.sourceline, target.find("station").get("name"))
    if moveto is not None:
        entity = next(m.Entity(c.tag) for c in moveto if isinstance(c.tag, str))
        return m.MoveTo(el.sourceline, entity, moveto.get("onErrorTask"))
    return m.Stop(el.sourceline)  # E-TASK-007: <motion/> without a child stops too


def _parameter(el: Any) -> m.Command:
    s = el.find("set")
    return m.SetParameter(el.sourceline, s.get("key").strip(), s.get("value").strip())


def _surveillance(el: Any) -> m.Command:
    grab = el.find("grab")
    if grab is not None:
        return m.Grab(
            el.sourceline,
            grab.get("filename").strip(),
            _flag(grab, "grabscan"),
            _flag(grab, "grabimage"),
            _flag(grab, "autoobservation"),
        )
    return m.MoveCamera(el.sourceline, el.find("movecamera").get("position"))


def _audio(el: Any) -> m.Command:
    speak = el.find("speak")
    if speak is not None:
        return m.Speak(el.sourceline, speak.get("text"))
    return m.Play(el.sourceline, el.find("play").get("filename").strip())


def _turnhead(el: Any) -> m.Command:
    return m.TurnHead(el.sourceline, _num(el.get("angle")))


def _date(c: Any) -> m.WaitEvent:
    fields = ("year", "month", "day", "hour", "minute", "second")
    return m.Date(**{f: int(c.get(f)) if c.get(f) is not None else None for f in fields})


def _direction(c: Any) -> m.Direction | None:
    text = (c.get("direction") or "any").strip().lower()
    if text not in m.DIRECTIONS:
        known = ", ".join(m.DIRECTIONS)
        reason = f"{c.tag}: unknown direction {c.get('direction')!r} (E-TASK-011: one of {known})"
        raise ProgramError(reason, c.sourceline)
    return m.DIRECTIONS[text]


def _random(c: Any) -> m.WaitEvent:
    lo, hi = _num(c.get("min")), _num(c.get("max"))
    if lo > hi:  # E-XML-009: "min greater than max is a task error"
        raise ProgramError(f"random: min {lo:g} ms is greater than max {hi:g} ms", c.sourceline)
    return m.Random(lo, hi)


_WAIT_EVENTS: dict[str, Callable[[Any], m.WaitEvent]] = {
    "collision": lambda c: m.Collision(),
    "movingobject": lambda c: m.Detected(m.Detection.MOVING_OBJECT),
    "movingobjects": lambda c: m.Detected(m.Detection.MOVING_OBJECT),  # E-XML-004
    "person": lambda c: m.Detected(m.Detection.PERSON),
    "ball": lambda c: m.Detected(m.Detection.BALL),
    "lostlocalization": lambda c: m.LostLocalization(),
    "lostlocalisation": lambda c: m.LostLocalization(),  # E-XML-004
    "target": lambda c: m.TargetReached(),
    "infrared": lambda c: m.Infrared(_direction(c)),
    "radar": lambda c: m.Radar(_direction(c)),
    "date": _date,
    "delay": lambda c: m.Delay(_num(c.get("amount"))),
    "userevent": lambda c: m.UserEvent(c.get("id").strip()),
    "random": _random,
    "batterycharge": lambda c: m.BatteryCharge(_num(c.get("limit"))),
}


def _wait(el: Any) -> m.Command:
    child = next((c for c in el if isinstance(c.tag, str)), None)
    event = None if child is None else _WAIT_EVENTS[child.tag](child)
    timeout = _opt_num(el, "timeout")
    return m.Wait(el.sourceline, event, timeout or None, el.get("timeoutlabel"))  # E-XML-009: 0 = no timeout


_COMMANDS: dict[str, Callable[[Any], m.Command]] = {
    "ioevent": _ioevent,
    "goto": _goto,
    "label": _label,
    "load": _load,
    "log": _log,
    "motion": _motion,
    "parameter": _parameter,
    "surveillance": _surveillance,
    "audio": _audio,
    "turnhead": _turnhead,
    "wait": _wait,
}
