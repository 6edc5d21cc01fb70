"""``python -m pltf.stubgen.pltf_client [--check] [--out DIR]``: the same as ``python -m pltf.client._generate``."""

import sys

from pltf.stubgen.pltf_client import main

sys.exit(main())
