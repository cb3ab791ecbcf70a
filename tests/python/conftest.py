import os
import sys

# The package lives in a build tree (CMake copies it next to the compiled _core). PYTHONPATH wins when it names
# one (e.g. another build directory); otherwise fall back to the repository's build/python.
ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
BUILD_PY = os.path.join(ROOT, "build", "python")
if BUILD_PY not in sys.path:
    sys.path.append(BUILD_PY)
