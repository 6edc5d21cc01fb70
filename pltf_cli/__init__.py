"""pltf_cli."""
