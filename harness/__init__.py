"""What the tools' harnesses share (issue 31): the launcher that starts any target on ephemeral ports
(launch.py), the pcapng writer (pcapng.py) and free loopback ports (ports.py). It imports the standard library
alone, but for two lazy imports in launch.py's table of the toolkit's targets. See harness/README.md."""
