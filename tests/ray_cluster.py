"""A real local Ray cluster for the `ray` tier: a head and more nodes, all on 127.0.0.1 of this machine.

Ray's own multi-node test harness (``ray.cluster_utils.Cluster``) starts each node as its own raylet with its own
processes, so a test can place work on a node, kill that node and watch the rest go on. Every node binds
127.0.0.1 (``node_ip_address``), the dashboard is off and ``RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER=0``: nothing listens
beyond loopback. Without the ray extra the tier is skipped, unless ``PLTF_REQUIRE_RAY=1`` (``make test-ray``)
makes that a failure.

Use it in a test module::

    from tests.ray_cluster import ray_cluster  # noqa: F401  (the fixture)

    @pytest.mark.ray
    def test_x(ray_cluster): ...   # ray_cluster.address is the head's GCS address; the driver is connected
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from typing import Any

import pytest

LOOPBACK = "127.0.0.1"
NODE_ARGS: dict[str, Any] = {
    "num_cpus": 2,
    "node_ip_address": LOOPBACK,
    "object_store_memory": 80 * 1024 * 1024,
}


def ray_or_skip() -> Any:
    """The ray module, or skip the test (fail under PLTF_REQUIRE_RAY=1) when the extra is not installed."""
    # before the first import: Ray reads it once, at import (ray_constants.ENABLE_RAY_CLUSTER); set later, Ray
    # resolves 127.0.0.1 in ray.init(address=...) to this machine's outward address, where no node listens
    os.environ["RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER"] = "0"
    try:
        import ray
    except ImportError:
        if os.environ.get("PLTF_REQUIRE_RAY") == "1":
            raise
        pytest.skip("the ray extra is not installed (make test-ray installs it)")
    return ray


def start_cluster(nodes: int = 2) -> Any:
    """A head and ``nodes - 1`` more nodes on 127.0.0.1, the driver connected to the head."""
    ray = ray_or_skip()
    os.environ["RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER"] = "0"
    from ray.cluster_utils import Cluster

    cluster = Cluster(initialize_head=True, head_node_args={**NODE_ARGS, "include_dashboard": False})
    for _ in range(nodes - 1):
        cluster.add_node(**NODE_ARGS)
    cluster.wait_for_nodes()
    ray.init(address=cluster.address, ignore_reinit_error=True, log_to_driver=False)
    return cluster


def stop_cluster(cluster: Any) -> None:
    ray = ray_or_skip()
    ray.shutdown()
    cluster.shutdown()


@pytest.fixture(scope="module")
def ray_cluster() -> Iterator[Any]:
    """A two-node cluster for the tests of one module (starting one costs seconds)."""
    cluster = start_cluster(2)
    try:
        yield cluster
    finally:
        stop_cluster(cluster)
