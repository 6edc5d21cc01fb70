"""The doors' rules one by one (gui/doors.py, gui/targets.py, gui/control.py), without sockets: which Host, which
Origin, which target, whose command. The HTTP and browser sides are in test_doors.py and test_doors_browser.py."""

from __future__ import annotations

from pathlib import Path

import pytest

from pltf.gui.control import COMMANDS, Control
from pltf.gui.doors import Doors, is_loopback, split_host
from pltf.gui.network_ini import NetworkIni
from pltf.gui.targets import TargetList
from pltf.spec.model import load_telegrams


@pytest.mark.parametrize(
    ("text", "split"),
    [
        ("127.0.0.1:8080", ("127.0.0.1", 8080)),
        ("[::1]:8080", ("::1", 8080)),
        ("[::1]", ("::1", None)),
        ("::1", ("::1", None)),
        ("LocalHost.:80", ("localhost", 80)),
        ("evil.example", ("evil.example", None)),
        ("", ("", None)),
    ],
)
def test_split_host(text: str, split: tuple[str, int | None]) -> None:
    assert split_host(text) == split


@pytest.mark.parametrize(
    ("listen", "host", "allowed"),
    [
        ("127.0.0.1", "127.0.0.1:8080", True),
        ("127.0.0.1", "127.3.4.5:8080", True),  # all of 127.0.0.0/8 is loopback
        ("127.0.0.1", "localhost:8080", True),
        ("127.0.0.1", "[::1]:8080", True),
        ("127.0.0.1", "evil.example:8080", False),  # a rebinding page's name
        ("127.0.0.1", "localhost.evil.example:8080", False),
        ("127.0.0.1", "192.168.0.5:8080", False),  # not the address it listens on
        ("127.0.0.1", "hall.example:8080", True),  # --allow-host hall.example
        ("192.168.0.5", "192.168.0.5:8080", True),
        ("0.0.0.0", "192.168.0.5:8080", True),  # a wildcard listen: every address of the machine
        ("0.0.0.0", "evil.example:8080", False),  # but not a name
        ("127.0.0.1", None, False),
    ],
)
def test_the_host_must_be_one_of_the_gateways_names(listen: str, host: str | None, allowed: bool) -> None:
    why = Doors(listen, frozenset({"Hall.Example"})).host_refusal(host)
    assert (why is None) == allowed
    if why is not None:
        assert "--allow-host" in why


@pytest.mark.parametrize(
    ("origin", "allowed"),
    [
        (None, True),  # not a page: the token decides
        ("http://127.0.0.1:8080", True),
        ("http://localhost:8080", True),
        ("http://[::1]:8080", True),
        ("http://127.0.0.1:3000", False),  # another program's page on this machine
        ("http://localhost", False),  # port 80
        ("http://evil.example:8080", False),
        ("null", False),
        ("https://hall.example", True),  # --allow-host: through a proxy, any port
    ],
)
def test_an_origin_must_name_an_allowed_host(origin: str | None, allowed: bool) -> None:
    assert (Doors("127.0.0.1", frozenset({"hall.example"})).origin_refusal(origin, 8080) is None) == allowed


def test_loopback() -> None:
    assert all(is_loopback(h) for h in ("localhost", "127.0.0.1", "127.9.9.9", "::1", "[::1]"))
    assert not any(is_loopback(h) for h in ("0.0.0.0", "::", "192.168.0.5", "example.com", ""))


def test_targets_on_the_list(tmp_path: Path) -> None:
    ini = NetworkIni(tmp_path / "Network.ini")
    ini.add("10.0.0.7:10002")
    targets = TargetList("127.0.0.1:10000", ini, frozenset({"[::1]:10000"}))
    for ok in ("127.0.0.1:10000", "10.0.0.7:10002", "[::1]:10000", "::1:10000"):
        assert targets.refusal(ok) is None, ok
    for refused in ("127.0.0.1:10002", "localhost:10000", "10.0.0.8:10002", "192.168.0.1:22"):
        why = targets.refusal(refused)
        assert why is not None and "--allow-target" in why, refused
    assert TargetList("127.0.0.1:10000", ini, any_target=True).refusal("192.168.0.1:22") is None


def test_the_commands_are_the_requests_without_a_reply() -> None:
    """guide 6.1 (erratum E-GUI-006): the answered requests read; every other request is a command."""
    telegrams = load_telegrams()
    assert {t.id for t in telegrams} == set(COMMANDS) | {t.id for t in telegrams if t.answered}
    moving = ("CMD_MOVE_VEL", "CMD_MOVE_ABS", "CMD_MOVE_REL", "CMD_MOVE_PATH", "CMD_MOVE_TO_STATION", "CMD_START")
    changing = ("CMD_SET_MODE", "CMD_SET_FRM_PLTF", "CMD_SET_PLTF_PARAM", "CMD_SET_MAP", "CMD_SET_DIGOUT", "CMD_EXIT")
    assert set(moving + changing) <= set(COMMANDS.values())
    assert not {"CMD_GET_STATUS", "CMD_GET_POSITION", "CMD_GET_MAP", "CMD_GET_PLTF_PARAM"} & set(COMMANDS.values())


def test_one_driver() -> None:
    c = Control()
    c.join("a", "tab 1")
    c.join("b", "tab 2")
    assert c.refusal("a") is None and c.refusal("b") is None  # nobody drives
    assert c.claim("a") and not c.claim("b")
    assert c.refusal("a") is None
    reason = c.refusal("b")
    assert reason is not None and reason[0] == "viewer" and "tab 1" in reason[1]
    assert c.view("b") == {
        "event": "control",
        "holder": "tab 1",
        "you": False,
        "read_only": False,
        "message": "tab 1 drives; you watch",
    }
    assert c.take("b") and c.view("b")["you"] and not c.view("a")["you"]
    assert not c.leave("a") and c.leave("b") and c.holder is None


def test_read_only_has_no_driver() -> None:
    c = Control(read_only=True)
    c.join("a", "tab 1")
    assert not c.claim("a") and not c.take("a") and c.holder is None
    reason = c.refusal("a")
    assert reason is not None and reason[0] == "read_only"
