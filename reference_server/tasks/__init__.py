"""The task interpreter (guide 4.5, 6.5 Program/Task): XML programs on the platform and from a remote computer.

``program`` compiles a validated document into ``model`` objects; ``interpreter`` runs them sans-IO against
a ``facade.Machine``: ``local`` (inside the reference server) or ``remote`` (socket commands through
clients.pltf_client). Decisions: spec/errata/tasks.yaml (E-TASK-nnn).
"""
