"""Baseline forwarders for ``proxy.get_position`` (benchmarks/bench_proxy.py): the floor of a user-space forwarder.

``forward.c`` and ``forward.py`` have the design of ``pltf proxy``'s forwarding core (proxy/network.py: one thread
per direction, blocking ``recv``, send at once, a FIN passed on as a FIN) and nothing else. Each is run as its own
process: ``forward TARGET_PORT`` listens at a free port of 127.0.0.1, prints ``proxy listening at
127.0.0.1:PORT`` and forwards one connection at a time to 127.0.0.1:TARGET_PORT.
"""
