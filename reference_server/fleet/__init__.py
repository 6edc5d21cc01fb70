"""A fleet in one world (issue 30): ``pltf serve --fleet FILE|N``.

Modules: config (the fleet file and ``--fleet N``), places (free places of a map), bodies (one pymunk space and
one array of the platforms' outlines), fleet (the platforms, booted, ticked and retired together; sans-IO),
network (the asyncio shell: one clock, each platform on its own ports), cli (``pltf serve --fleet``).
"""
