"""``python -m pltf.reference_server``: see reference_server.cli."""

import sys

from pltf.reference_server.cli import main

sys.exit(main())
