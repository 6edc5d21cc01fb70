"""The simulated platform's world (issue 5): map geometry in pymunk, sensors, localization, planning, motion.

Modules: geometry (the map as arrays), raycast (numpy ray casting), physics (pymunk bodies), sensors (laser,
ultrasonic, observations), localization, planner (visibility graph), paths and ipo (interpolator and
controller), automatic (move commands), replay (post-process recording), motion (the motion modes), world
(the whole platform, stepped in simulated time). Sans-IO throughout: ``now``, ``dt`` and a seeded
``random.Random`` come from the caller.
"""

from pltf.reference_server.world.geometry import MapGeometry
from pltf.reference_server.world.planner import PlannerState
from pltf.reference_server.world.world import World

__all__ = ["MapGeometry", "PlannerState", "World"]
