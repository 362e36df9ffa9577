"""Pipeline tests: make the fake solver importable here and in the dask workers spawned from here
(spawned processes inherit sys.path)."""

import sys
from pathlib import Path

HERE = str(Path(__file__).resolve().parent)
if HERE not in sys.path:
    sys.path.insert(0, HERE)
