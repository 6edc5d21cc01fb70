"""Guide 6.3 CMD_EXIT and the field-evidence CMD_SHUTDOWN_HOST: they stop the target, so they run last and only
with --allow-shutdown."""

from __future__ import annotations

from pltf.conformance_tests.catalogue import Level, case
from pltf.conformance_tests.context import CaseContext
from pltf.conformance_tests.outcome import ConnectionClosed, Fail
from pltf.conformance_tests.wire import wait_port_closed
from pltf.spec.codec import build


@case(
    "6.3/CMD_SHUTDOWN_HOST/accepted",
    destructive=True,
    errata=("E-CMD-012",),
    level=Level.MAY,
    requirement="field evidence id 99 CMD_SHUTDOWN_HOST (layout unknown, erratum E-CMD-012): accepted without a "
    "reply; a simulator does not shut its host down",
    telegrams=("CMD_SHUTDOWN_HOST",),
)
def shutdown_host(ctx: CaseContext) -> None:
    s = ctx.session()
    s.send(build("request", "CMD_SHUTDOWN_HOST", payload=b""))
    try:
        s.request(build("request", "CMD_GET_STATUS"))
    except ConnectionClosed:
        ctx.deviate("E-CMD-012", 0, "CMD_SHUTDOWN_HOST closed the connection")
        ctx.reset_session()


@case(
    "6.3/CMD_EXIT/shuts-down",
    destructive=True,
    requirement='guide 6.3 CMD_EXIT: "Shut the platform down." - the connections close and the ports stop listening',
    telegrams=("CMD_EXIT",),
)
def exit_shuts_down(ctx: CaseContext) -> None:
    s = ctx.session()
    s.send(build("request", "CMD_EXIT"))
    if not s.wait_closed(ctx.wall(10.0)):
        raise Fail("CMD_EXIT: the connection stayed open")
    ctx.reset_session()
    if not wait_port_closed(ctx.config.host, ctx.config.port, max(5.0, ctx.wall(10.0))):
        raise Fail("CMD_EXIT: the port still takes connections")
