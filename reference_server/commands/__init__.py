"""The command handlers of guide 6.3, one module per command family of the guide's table (6.1):

| module | family |
|---|---|
| ``canbus`` | CAN Communication Commands |
| ``operation`` | Platform Operation Commands (and the program hook of MODE_MOTION_PROGRAM) |
| ``request`` | Request Status Commands |
| ``motion`` | Motion Commands (guide 4.3: which has an effect in which motion mode) |
| ``data`` | Platform Data Commands: documents, pose, parameters |
| ``special`` | Special Functions Commands |
| ``debug`` | Debug Commands and the identifiers known only from field code |

Importing this package registers every handler into ``registry.HANDLERS``.
"""

from pltf.reference_server.commands import canbus, data, debug, motion, operation, request, special
from pltf.reference_server.commands.registry import ACCEPTED, HANDLERS, Handler, Outcome, handler_names, handles

__all__ = [
    "ACCEPTED",
    "HANDLERS",
    "Handler",
    "Outcome",
    "canbus",
    "data",
    "debug",
    "handler_names",
    "handles",
    "motion",
    "operation",
    "request",
    "special",
]
