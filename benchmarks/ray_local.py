"""A local Ray cluster on 127.0.0.1 for the benchmarks that run on Ray (fuzz_parallel, fleet_ray).

Ray reads RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER=0 (loopback addresses only) when it is imported: it is set before.
Without the ray extra, or when a node does not come up (a loaded machine), the caller gets None and a line on
stderr saying which rows are left out.
"""

from __future__ import annotations

import contextlib
import os
import sys
from collections.abc import Iterator
from typing import Any

NODE: dict[str, Any] = {"num_cpus": 2, "node_ip_address": "127.0.0.1", "object_store_memory": 80 * 1024 * 1024}


def say(text: str) -> None:
    print(f"  {text}, load {os.getloadavg()[0]:.1f}", file=sys.stderr)


@contextlib.contextmanager
def local_cluster(nodes: int, rows: str, **init: Any) -> Iterator[Any]:
    """``nodes`` nodes (the head included) with the driver connected; ``rows`` names what is left out without it."""
    os.environ["RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER"] = "0"
    try:
        import ray
        from ray.cluster_utils import Cluster
    except ImportError:
        say(f"no {rows} rows: the ray extra is not installed (pip install 'pltf-toolkit[ray]')")
        yield None
        return
    try:
        cluster = Cluster(initialize_head=True, head_node_args={**NODE, "include_dashboard": False})
        for _ in range(nodes - 1):
            cluster.add_node(**NODE)
        cluster.wait_for_nodes()
    except Exception as exc:  # Ray's own: a node that does not come up within its start-up time (a loaded machine)
        say(f"no {rows} rows: the local cluster did not start ({str(exc).splitlines()[0][:120]})")
        yield None
        return
    ray.init(address=cluster.address, log_to_driver=False, **init)
    try:
        yield cluster
    finally:
        ray.shutdown()
        cluster.shutdown()
