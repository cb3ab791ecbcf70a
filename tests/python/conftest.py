import os
import sys

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
BUILD_PY = os.path.join(ROOT, "build", "python")
if BUILD_PY not in sys.path:
    sys.path.insert(0, BUILD_PY)
