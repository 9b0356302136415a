"""The public API's docstrings are numpydoc (issue 51): every public function and class of
``bsdfkit.__all__`` and of the public subpackages, and the array methods of every registered
model, has a ``Parameters`` section when it takes parameters and a ``Returns`` section when it
returns a value, so a new callable cannot arrive without them.

    python tests/test_docstring_sections.py     # prints the count and what is missing
"""
import enum
import importlib
import inspect
import re

import pytest

import bsdfkit as bk

#: Modules whose ``__all__`` is the public API checked here.
PUBLIC_MODULES = ("bsdfkit", "bsdfkit.plot", "bsdfkit.io", "bsdfkit.render", "bsdfkit.spectral",
                  "bsdfkit.fitting", "bsdfkit.tuning", "bsdfkit.directions")
#: Methods of each registered model class checked besides its constructor (the class docstring).
MODEL_METHODS = ("eval", "pdf", "sample", "albedo", "eval_grad")

_SECTION = r"^{}\n-{{3,}}\s*$"


def has_section(doc: str, *titles: str) -> bool:
    return any(re.search(_SECTION.format(t), doc or "", re.M) for t in titles)


def public_callables() -> dict:
    """{qualified name: object}: the public functions and classes, each object once."""
    seen, out = set(), {}

    def add(name, obj):
        if id(obj) not in seen:
            seen.add(id(obj))
            out[name] = obj

    for modname in PUBLIC_MODULES:
        mod = importlib.import_module(modname)
        for name in mod.__all__:
            obj = getattr(mod, name)
            if inspect.isclass(obj) or inspect.isfunction(obj) or inspect.isbuiltin(obj):
                add(f"{modname}.{name}", obj)
    for cls in bk.MODELS:
        add(f"bsdfkit.{cls.__name__}", cls)
        for meth in MODEL_METHODS:
            fn = getattr(cls, meth, None)
            if fn is not None:
                owner = next(c for c in cls.__mro__ if meth in c.__dict__)
                add(f"bsdfkit.{owner.__name__}.{meth}", fn)
    return out


def _params(obj) -> list:
    try:
        sig = inspect.signature(obj)
    except (TypeError, ValueError):
        return []
    return [p for p in sig.parameters.values() if p.name not in ("self", "cls")]


def missing(obj) -> list:
    """The numpydoc sections ``obj``'s docstring lacks (an empty list: complete)."""
    doc = inspect.getdoc(obj) or ""
    if not doc:
        return ["docstring"]
    if inspect.isclass(obj):
        if issubclass(obj, (BaseException, enum.Enum)):
            return []   # a warning / an enumeration: its members are its documentation
        ctor = inspect.getdoc(obj.__init__) if "__init__" in obj.__dict__ else ""
        if _params(obj) and not has_section(doc, "Parameters", "Attributes") \
                and not has_section(ctor, "Parameters"):
            return ["Parameters"]
        return []
    out = []
    if _params(obj) and not has_section(doc, "Parameters"):
        out.append("Parameters")
    returns_none = inspect.signature(obj).return_annotation in (None, "None")
    if not returns_none and not has_section(doc, "Returns", "Yields"):
        out.append("Returns")
    return out


CALLABLES = public_callables()


def test_the_public_api_is_all_there():
    assert len(CALLABLES) > 100 and "bsdfkit.BxDF.eval" in CALLABLES and "bsdfkit.simplify" in CALLABLES


@pytest.mark.parametrize("name", sorted(CALLABLES))
def test_numpydoc_sections(name):
    lack = missing(CALLABLES[name])
    assert not lack, f"{name}: its docstring has no {' / '.join(lack)} section (numpydoc)"


if __name__ == "__main__":
    bad = {n: missing(o) for n, o in CALLABLES.items() if missing(o)}
    for n, lack in sorted(bad.items()):
        print(f"{n}: {', '.join(lack)}")
    print(f"{len(CALLABLES) - len(bad)} of {len(CALLABLES)} public callables have their numpydoc sections")
