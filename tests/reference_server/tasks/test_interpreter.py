"""The interpreter against a FakeMachine: scheduling, onErrorTask, pause/stop, conditions, every wait (facade level).

The socket-level tests (test_program_*.py) check the same behaviour on the reference server; these pin the
semantics of spec/errata/tasks.yaml at the facade seam, where a sensor can be switched at an exact instant.
"""

from __future__ import annotations

import pytest

from pltf.reference_server.tasks.facade import Target
from pltf.reference_server.tasks.interpreter import STEP_BUDGET, Interpreter
from pltf.reference_server.tasks.model import Entity
from pltf.reference_server.tasks.program import ProgramError, load_program
from pltf.spec.documents import DocumentError
from tests.reference_server.tasks.fake_machine import FakeMachine

DT = 0.02


def program(*tasks: str) -> bytes:
    return ("<program version='1.0'>" + "".join(tasks) + "</program>").encode()


def task(body: str, name: str = "main", priority: int = 0) -> str:
    return f"<task name='{name}' priority='{priority}'>{body}</task>"


def run(
    xml: bytes, fm: FakeMachine | None = None, until: float = 1.0, seed: int = 0
) -> tuple[Interpreter, FakeMachine]:
    fm = fm or FakeMachine()
    it = Interpreter(load_program(xml), fm, seed)
    it.start(0.0)
    step(it, 0.0, until)
    return it, fm


def step(it: Interpreter, t0: float, t1: float) -> None:
    n = round((t1 - t0) / DT)
    for k in range(1, n + 1):
        it.tick(t0 + k * DT)


def test_priorities_order_tasks_within_a_tick_and_handlers_do_not_start() -> None:
    xml = program(
        task("<log message='low'/>", "low", 1),
        task("<log message='high'/>", "high", 5),
        task("<log message='same as low, later in the document'/>", "low2", 1),
        task("<motion><moveto onErrorTask='handler'><trackedball/></moveto></motion>", "mover", 0),
        task("<log message='handler'/>", "handler", 9),
    )
    it, fm = run(xml, until=0.0)
    messages = [a[2] for a in fm.of("log") if not a[2].startswith("task ")]
    assert messages == ["high", "low", "same as low, later in the document", "handler"]
    assert it.finished


def test_on_error_task_runs_then_the_caller_goes_on() -> None:
    xml = program(
        task("<motion><moveto onErrorTask='recover'><trackedperson/></moveto></motion><log message='after'/>"),
        task("<wait><delay amount='100'/></wait><log message='recovered'/>", "recover"),
    )
    it, fm = run(xml, until=0.0)
    assert [a[2] for a in fm.of("log") if a[1] == "info" and not a[2].startswith("task")] == []
    step(it, 0.0, 0.2)
    msgs = [a[2] for a in fm.of("log") if not a[2].startswith("task")]
    assert msgs == ["recovered", "after"]
    assert not fm.of("move")


def test_moveto_without_handler_ends_the_task_and_others_go_on() -> None:
    xml = program(
        task("<motion><moveto><trackedball/></moveto></motion><log message='never'/>"),
        task("<log message='other'/>", "other"),
    )
    _it, fm = run(xml, until=0.0)
    texts = [a[2] for a in fm.of("log")]
    assert "never" not in texts and "other" in texts
    assert any("failed" in t and "trackedball" in t for t in texts)


def test_moveto_approaches_a_tracked_entity_and_docks_at_the_charging_station() -> None:
    fm = FakeMachine()
    fm.entities[Entity.PERSON] = Target(3000.0, 4000.0, None)
    fm.entities[Entity.CHARGING_STATION] = Target(100.0, 200.0, 90.0)
    xml = program(
        task("<motion><moveto><trackedperson/></moveto></motion><motion><moveto><chargingstation/></moveto></motion>")
    )
    run(xml, fm, until=0.0)
    assert fm.of("move") == [("move", 2520, 3360, 53.13), ("move", 100, 200, 90.0)]


def test_goto_conditions_on_inputs_outputs_and_parameters() -> None:
    fm = FakeMachine()
    fm.inputs[2] = 1
    xml = program(
        task(
            "<goto label='a' condition='DI3==1'/><log message='skipped'/><label name='a'/>"
            "<ioevent><digitalout D2='1'/></ioevent>"
            "<goto label='b' condition='DO2!=1'/><log message='DO2 is 1'/><label name='b'/>"
            "<goto label='c' condition='param:MaxTransVel==600.0'/><log message='skipped too'/><label name='c'/>"
            "<goto label='d' condition='false'/><log message='false does not jump'/><label name='d'/>"
            "<goto label='e' condition='param:Unknown==1'/><label name='e'/><log message='never'/>"
        )
    )
    run(xml, fm, until=0.0)
    texts = [a[2] for a in fm.of("log")]
    assert texts[:2] == ["DO2 is 1", "false does not jump"]
    assert "never" not in texts and any("Unknown" in t for t in texts)


def test_a_loop_without_waits_yields_after_its_budget_and_others_still_run() -> None:
    xml = program(task("<label name='l'/><goto label='l'/>", "spin", 5), task("<log message='alive'/>", "other"))
    it, fm = run(xml, until=0.1)
    assert ("log", "info", "alive") in fm.actions
    assert any(str(STEP_BUDGET) in a[2] for a in fm.of("log"))
    assert not it.finished


@pytest.mark.parametrize(
    ("element", "switch"),
    [
        ("<collision/>", lambda fm: fm.flags.update(collision=True)),
        ("<movingobject/>", lambda fm: fm.flags.update(movingobject=True)),
        ("<movingobjects/>", lambda fm: fm.flags.update(movingobject=True)),
        ("<person/>", lambda fm: fm.flags.update(person=True)),
        ("<ball/>", lambda fm: fm.flags.update(ball=True)),
        ("<lostlocalization/>", lambda fm: fm.flags.update(lost=True)),
        ("<lostlocalisation/>", lambda fm: fm.flags.update(lost=True)),
        ("<target/>", lambda fm: setattr(fm, "reached", True)),
        ("<infrared direction='left'/>", lambda fm: fm.ir.__setitem__(2, True)),
        ("<radar/>", lambda fm: fm.radar_on.__setitem__(3, True)),
        ("<userevent id='7'/>", lambda fm: fm.events.add("7")),
        ("<batterycharge limit='80'/>", lambda fm: setattr(fm, "battery", 80.0)),
    ],
)
def test_each_sensor_wait_ends_when_its_event_comes(element: str, switch: object) -> None:
    xml = program(task(f"<wait>{element}</wait><log message='over'/>"))
    it, fm = run(xml, until=0.5)
    assert ("log", "info", "over") not in fm.actions
    switch(fm)  # type: ignore[operator]
    step(it, 0.5, 0.52)
    assert ("log", "info", "over") in fm.actions


def test_infrared_in_another_direction_does_not_end_the_wait() -> None:
    fm = FakeMachine()
    fm.ir[0] = True
    _it, fm = run(program(task("<wait><infrared direction='back'/></wait><log message='over'/>")), fm, until=0.2)
    assert ("log", "info", "over") not in fm.actions


def test_delay_random_date_and_timeouts_in_simulated_time() -> None:
    xml = program(
        task(
            "<wait><delay amount='300'/></wait><log message='delay'/>"
            "<wait><random min='100' max='200'/></wait><log message='random'/>"
            "<wait timeout='250' timeoutlabel='late'><person/></wait><log message='not here'/>"
            "<label name='late'/><log message='timeout'/>"
            "<wait timeout='100'><ball/></wait><log message='timeout without label: next'/>"
            "<wait><date hour='0' minute='0' second='3'/></wait><log message='date'/>"
        )
    )
    _it, fm = run(xml, until=4.0)
    times = {}
    fm2 = FakeMachine()
    it2 = Interpreter(load_program(xml), fm2, 0)
    it2.start(0.0)
    for k in range(1, 201):
        for p in it2.tick(k * DT):
            if p.kind == "log":
                times[p.text.split("] ")[1]] = round(p.now, 2)
    assert times["delay"] == 0.3
    assert 0.4 <= times["random"] <= 0.5
    assert times["timeout"] == round(times["random"] + 0.26, 2) or times["timeout"] == round(times["random"] + 0.24, 2)
    assert "not here" not in times
    assert times["date"] == 3.0
    assert [a[2] for a in fm.of("log") if not a[2].startswith("task")][-1] == "date"


def test_same_seed_same_random_delays_other_seed_other() -> None:
    xml = program(task("<wait><random min='0' max='60000'/></wait><log message='x'/>"))

    def ended(seed: int) -> float:
        it = Interpreter(load_program(xml), FakeMachine(), seed)
        it.start(0.0)
        for k in range(1, 3001):
            if any(p.kind == "log" for p in it.tick(k * DT)):
                return k * DT
        raise AssertionError("no end")

    assert ended(3) == ended(3)
    assert ended(3) != ended(4)


def test_pause_freezes_delays_and_stop_ends_every_task() -> None:
    xml = program(task("<wait><delay amount='1000'/></wait><log message='over'/>"))
    fm = FakeMachine()
    it = Interpreter(load_program(xml), fm, 0)
    it.start(0.0)
    step(it, 0.0, 0.5)
    it.pause(0.5)
    step(it, 0.5, 5.0)
    assert ("log", "info", "over") not in fm.actions
    it.resume(5.0)
    step(it, 5.0, 5.48)
    assert ("log", "info", "over") not in fm.actions
    step(it, 5.48, 5.52)
    assert ("log", "info", "over") in fm.actions
    it2 = Interpreter(load_program(xml), FakeMachine(), 0)
    it2.start(0.0)
    it2.stop(0.1)
    assert it2.finished and not it2.running


def test_every_action_reaches_the_facade() -> None:
    fm = FakeMachine(files={"office.map", "office.rm"})
    xml = program(
        task(
            "<load map='office.map' roadmap='office.rm'/><ioevent><digitalout D1='1' D12='0'/></ioevent>"
            "<parameter><set key='MaxTransVel' value='400'/></parameter><motion stop='1'/>"
            "<motion><settarget><coord x='1000.5' y='-20' angle='90'/></settarget></motion>"
            "<motion><settarget><station name='Kitchen'/></settarget></motion>"
            "<surveillance><grab filename='g' grabscan='true' grabimage='1'/></surveillance>"
            "<surveillance><movecamera position='pan=1'/></surveillance><audio><speak text='hi'/></audio>"
            "<audio><play filename='a.wav'/></audio><turnhead angle='-45'/>"
        )
    )
    run(xml, fm, until=0.0)
    kinds = [a for a in fm.actions if a[0] != "log"]
    assert kinds == [
        ("load", "office.map", "office.rm"),
        ("digout", (1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, 0)),
        ("param", "MaxTransVel", "400"),
        ("stop",),
        ("move", 1000, -20, 90.0),
        ("station", "Kitchen"),
        ("grab", "g", True, True),
        ("camera", "pan=1"),
        ("speak", "hi"),
        ("play", "a.wav"),
        ("head", -45.0),
    ]


@pytest.mark.parametrize(
    ("body", "message"),
    [
        ("<goto label='nowhere'/>", "no label 'nowhere'"),
        ("<wait timeout='1' timeoutlabel='x'/>", "no label 'x'"),
        ("<label name='a'/><label name='a'/>", "label 'a' defined twice"),
        ("<motion><moveto onErrorTask='ghost'><trackedball/></moveto></motion>", "onErrorTask 'ghost'"),
        ("<wait><random min='5' max='1'/></wait>", "min 5 ms is greater than max 1 ms"),
        ("<wait><radar direction='up'/></wait>", "unknown direction 'up'"),
    ],
)
def test_programs_that_cannot_run_are_refused_with_the_line(body: str, message: str) -> None:
    with pytest.raises(ProgramError, match=message) as info:
        load_program(program(task(body)))
    assert info.value.line == 1


def test_schema_violations_keep_the_schema_message() -> None:
    with pytest.raises(DocumentError, match="digitalout"):
        load_program(program(task("<ioevent><digitalout D1='2'/></ioevent>")))
