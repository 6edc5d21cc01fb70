"""``pltf proxy``, ``pltf replay`` and ``pltf dissector``: see the traffic, keep it, replay it, open it in Wireshark.

- ``tap``: live decoding of one direction of a proxied connection (sans-IO, the codec of spec/).
- ``session``: the session file (JSON lines) written and read; ``capture``: the pcapng recording (fuzz/pcapng.py).
- ``view``: the live view (one line per telegram, filtered by telegram name).
- ``network``: the forwarding core (asyncio; the only module of the proxy that touches sockets).
- ``replay`` (plan and judgement, sans-IO), ``compare`` (field by field, spec/volatile.yaml), ``replay_io``
  (asyncio) and ``report``: ``pltf replay``.
- ``dissector``: the Wireshark Lua dissector generated from spec/ (``pltf.lua`` is its committed output).
"""
