"""The case modules (registration happens at import) and the order in which the suite runs their groups.

The transport first (framing, ports: nothing else can be judged if it fails), then the state chart, the other
commands in every state, the replies, parameters, documents, CAN, special functions, motion and task programs;
CMD_EXIT (final) last.
"""

from pltf.conformance_tests.cases import (  # noqa: F401 - imported for registration
    can,
    commands,
    documents,
    final,
    framing,
    motion,
    motion_ignored,
    parameters,
    ports,
    programs,
    replies,
    special,
    state,
)

GROUP_ORDER = (
    "framing",
    "ports",
    "state",
    "commands",
    "replies",
    "parameters",
    "documents",
    "can",
    "special",
    "motion",
    "programs",
    "final",
)
