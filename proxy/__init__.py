"""``pltf proxy``, ``pltf replay`` and ``pltf dissector``: see the traffic, keep it, replay it, open it in Wireshark.

- ``network``: the forwarding core (asyncio, plain sockets; the only module of the proxy with sockets and a clock).
- ``offload``: the recorder in a process of its own, fed through a pipe (nothing delays a forwarded byte).
- ``recorder``: decode (``tap``, the codec of spec/), show (``view``), keep (``session``: JSON lines;
  ``capture``: pcapng through harness/pcapng.py), sans-IO.
- ``replay`` (plan and judgement, sans-IO), ``compare`` (field by field, spec/volatile.yaml), ``replay_io``
  (asyncio) and ``report`` (text, JUnit): ``pltf replay``.
- ``dissector``: the Wireshark Lua dissector generated from spec/ (``lua/runtime.lua`` interprets the tables it
  writes; ``pltf.lua`` is its committed output).
See proxy/README.md.
"""
