"""The Examples of bsdfkit's docstrings run as doctests: every ``>>>`` line of every module of the
package, in a scratch directory (an example may write a file)."""
import doctest
import importlib
from pathlib import Path

import numpy as np
import pytest

import bsdfkit

PKG = Path(bsdfkit.__file__).resolve().parent


def _modules_with_examples():
    """Module names of the package's sources that hold a ``>>>`` example (read, not imported)."""
    names = []
    for src in sorted(PKG.rglob("*.py")):
        if ">>> " in src.read_text(encoding="utf-8"):
            parts = src.relative_to(PKG.parent).with_suffix("").parts
            names.append(".".join(parts[:-1] if parts[-1] == "__init__" else parts))
    return names


MODULES = _modules_with_examples()
NUMPY_PRINT_DEFAULTS = dict(edgeitems=3, threshold=1000, floatmode="maxprec", precision=8, suppress=False,
                            linewidth=75, nanstr="nan", infstr="inf", sign="-", formatter=None, legacy=False)


def test_there_are_examples():
    assert "bsdfkit" in MODULES


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    mod = importlib.import_module(name)
    finder = doctest.DocTestFinder(exclude_empty=True)
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    tests = [t for t in finder.find(mod, name, globs={"np": np}) if t.examples]
    assert tests, f"{name}: no examples found"
    # numpy's default print options: the examples show arrays as a user sees them, and a library
    # imported earlier in the suite may have changed them (a legacy "1.13" sign pad: "[ 1.,  0.]")
    with np.printoptions(**NUMPY_PRINT_DEFAULTS):
        for t in tests:
            runner.run(t)
    res = runner.summarize(verbose=False)
    assert res.failed == 0, f"{name}: {res.failed} of {res.attempted} doctest examples failed (see the output above)"
