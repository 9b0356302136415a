"""Helpers of the kernel lab's tests (tools/perf/tests, run by scripts/perf-test, not by scripts/test)."""
import importlib.util
import sys
from pathlib import Path

PERF = Path(__file__).resolve().parents[1]   # tools/perf
ROOT = PERF.parents[1]                       # the repository


def load_tool(script):
    """A script of tools/perf/ (e.g. "mca.py") imported as a module, its directory on sys.path while
    it loads (the scripts import tools/perf/_machine.py as a sibling)."""
    path = PERF / script
    sys.path.insert(0, str(path.parent))
    try:
        spec = importlib.util.spec_from_file_location("perf_" + path.stem, path)
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
    finally:
        sys.path.remove(str(path.parent))
    return mod
