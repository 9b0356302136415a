"""Readable model specs for the command line and the notebooks, and one example model per class.

A spec is a model name followed by its parameters, words separated by spaces::

    conductor metal=Cu alpha=0.2        -> Conductor.from_metal("Cu", alpha=0.2)
    conductor reflectance=0.9,0.6,0.3   -> Conductor.from_reflectance((0.9, 0.6, 0.3))
    diffuse 0.8,0.5,0.2                 -> Diffuse((0.8, 0.5, 0.2))
    dielectric eta=1.5 alpha=0.1        -> Dielectric(1.5, alpha=0.1)
    difftrans 0.5 0.4                   -> DiffuseTransmission(0.5, 0.4)
    filament_standard metallic=1 roughness=0.3

The model name is a class of ``bsdfkit.MODELS`` (case-insensitive, as ``FilamentStandard``,
``filamentstandard`` or ``filament_standard``) or an alias (:func:`aliases`). Parameters are
those of the class's constructor, positional or ``key=value``; a key ``X`` naming an alternative
constructor ``from_X`` (``metal=`` for ``Conductor.from_metal``, ``reflectance=`` for
``Conductor.from_reflectance``) switches to it. Values: numbers, ``r,g,b`` triples,
``true``/``false``, ``none``, a model in brackets (the children of the composite models:
``mix [diffuse 0.8] [conductor metal=Au alpha=0.3] 0.3``), anything else is a string
(``masking=separable``).

Everything is derived from the model registry (``bsdfkit.models.registry``: class names,
``aliases``, ``examples``) and the constructors' signatures, so a new model class is accepted (and
listed in error messages) without touching this file; its first example is its gallery row.
"""
from __future__ import annotations

import inspect
import re

from . import registry

__all__ = ["parse_spec", "parse_specs", "example_model", "example_spec", "model_names", "usage", "to_spec",
           "aliases", "SpecError"]


class SpecError(ValueError):
    """A model spec that does not name a model or its parameters; the message lists valid ones."""


def _models():
    return registry.classes()


def aliases() -> dict:
    """Short names accepted besides the class names: ``{alias: class name}`` (from the registry)."""
    return {a: c.__name__ for c in _models() for a in c.aliases}


def _snake(name: str) -> str:
    return re.sub(r"(?<=[a-z0-9])(?=[A-Z])", "_", name).lower()


def _key(word: str) -> str:
    return word.lower().replace("_", "").replace("-", "")


def model_names() -> dict:
    """Every accepted model name (snake_case class names and aliases) -> class."""
    classes = {c.__name__: c for c in _models()}
    names = {_snake(n): c for n, c in classes.items()}
    names.update({a: classes[t] for a, t in aliases().items() if t in classes})
    return names


def _lookup(word: str):
    for name, cls in model_names().items():
        if _key(name) == _key(word):
            return cls
    return None


def _alternatives(cls) -> dict:
    """``{"metal": Conductor.from_metal, ...}``: classmethods ``from_X`` of the class."""
    out = {}
    for name in dir(cls):
        if name.startswith("from_") and callable(getattr(cls, name)):
            out[name[len("from_"):]] = getattr(cls, name)
    return out


def _params(fn, skip_first=False):
    ps = [p for p in inspect.signature(fn).parameters.values() if p.name not in ("self", "cls")
          and p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)]
    return ps[1:] if skip_first else ps


def _fmt_param(p) -> str:
    if p.default is inspect.Parameter.empty:
        return p.name
    return f"{p.name}={p.default}" if isinstance(p.default, str) else f"{p.name}={p.default!r}"


def _signature_text(cls) -> str:
    name = _snake(cls.__name__)
    lines = [f"  {name} " + " ".join(_fmt_param(p) for p in _params(cls.__init__))]
    for key, fn in _alternatives(cls).items():
        first = _params(fn)[0].name
        rest = " ".join(_fmt_param(p) for p in _params(fn, skip_first=True))
        choices = getattr(fn, "choices", None)   # an alternative constructor may list its accepted values
        value = "|".join(choices) if choices else first.upper()
        lines.append(f"  {name} {key}={value} {rest}".rstrip())
    return "\n".join(lines)


def usage(cls=None) -> str:
    """The valid models and their parameters (of one class, or of every model)."""
    classes = [cls] if cls is not None else list(_models())
    head = "" if cls is not None else (
        "valid models (name, then positional values or key=value parameters; RGB as r,g,b):\n")
    text = head + "\n".join(_signature_text(c) for c in classes)
    if cls is None:
        text += "\naliases: " + ", ".join(f"{a} = {_snake(t)}" for a, t in aliases().items())
    return text


def _words(spec) -> list:
    """The words of a spec (a string or a list of words): split at spaces, except inside brackets
    (a nested model spec is one word, ``[diffuse 0.8]``)."""
    text = spec if isinstance(spec, str) else " ".join(map(str, spec))
    words, cur, depth = [], "", 0
    for ch in text:
        if ch == "[":
            depth += 1
        elif ch == "]":
            depth -= 1
            if depth < 0:
                raise SpecError(f"unbalanced ']' in {text!r}")
        if ch.isspace() and depth == 0:
            if cur:
                words.append(cur)
            cur = ""
        else:
            cur += ch
    if depth:
        raise SpecError(f"unbalanced '[' in {text!r}")
    if cur:
        words.append(cur)
    return words


def _value(text: str):
    if text.startswith("[") and text.endswith("]"):
        return parse_spec(text[1:-1])
    low = text.lower()
    if low in ("true", "false"):
        return low == "true"
    if low == "none":
        return None
    parts = text.split(",")
    vals = []
    for p in parts:
        try:
            vals.append(int(p) if re.fullmatch(r"[+-]?\d+", p.strip()) else float(p))
        except ValueError:
            return text
    return vals[0] if len(vals) == 1 else vals


def parse_spec(spec):
    """The model described by ``spec`` (a string, or a list of its words).

    Raises :class:`SpecError` (a ValueError) naming the problem and listing the valid models
    or the model's parameters; a ValueError/TypeError of the constructor (an out-of-range value)
    is re-raised as SpecError with the spec in front.
    """
    words = _words(spec)
    text = " ".join(words)
    if not words:
        raise SpecError("empty model spec\n" + usage())
    cls = _lookup(words[0])
    if cls is None:
        raise SpecError(f"unknown model {words[0]!r}\n" + usage())
    args, kwargs = [], {}
    for w in words[1:]:
        if "=" in w and not w.startswith("["):
            k, v = w.split("=", 1)
            if not k.isidentifier():
                raise SpecError(f"bad parameter {w!r} in {text!r}; expected key=value\n" + usage(cls))
            if k in kwargs:
                raise SpecError(f"parameter {k!r} given twice in {text!r}")
            kwargs[k] = _value(v)
        else:
            if kwargs:
                raise SpecError(f"positional value {w!r} after key=value parameters in {text!r}")
            args.append(_value(w))
    target = cls
    alts = _alternatives(cls)
    chosen = [k for k in kwargs if k in alts and k not in {p.name for p in _params(cls.__init__)}]
    if len(chosen) > 1:
        raise SpecError(f"{text!r}: give one of {', '.join(k + '=' for k in chosen)}, not several\n" + usage(cls))
    if chosen:
        target = alts[chosen[0]]
        if args:
            raise SpecError(f"{text!r}: no positional values with {chosen[0]}=")
        args = [kwargs.pop(chosen[0])]
    sig = inspect.signature(target)
    if not any(p.kind == p.VAR_KEYWORD for p in sig.parameters.values()):
        unknown = [k for k in kwargs if k not in sig.parameters]
        if unknown:
            raise SpecError(f"{text!r}: {_snake(cls.__name__)} has no parameter {unknown[0]!r}; its parameters:\n"
                            + usage(cls))
    try:
        sig.bind(*args, **kwargs)
    except TypeError as e:
        raise SpecError(f"{text!r}: {e}\n" + usage(cls)) from None
    try:
        return target(*args, **kwargs)
    except (ValueError, TypeError) as e:
        raise SpecError(f"{text!r}: {e}") from None


def parse_specs(words) -> list:
    """Several specs separated by a ``+`` word (``conductor metal=Cu + diffuse 0.5``): a list of models."""
    words = _words(words)
    groups, cur = [], []
    for w in words:
        if w == "+":
            groups.append(cur)
            cur = []
        else:
            cur.append(w)
    groups.append(cur)
    return [parse_spec(g) for g in groups]


def example_spec(cls) -> str:
    """The gallery's spec of a model class: the first of its registered ``examples``."""
    ex = getattr(cls, "examples", None)
    if not ex:
        raise LookupError(f"{cls.__name__} declares no examples: add examples = {{label: spec}} to the class "
                          f"so the gallery, the demo and the contract tests can show it")
    return next(iter(ex.values()))


def example_model(cls):
    """The model of class ``cls`` described by its first registered example."""
    m = parse_spec(example_spec(cls))
    if type(m) is not cls:
        raise LookupError(f"the example spec of {cls.__name__} built a {type(m).__name__}")
    return m


def _same(a, b) -> bool:
    import numpy as np

    if a is None or b is None or isinstance(a, (str, bool)) or isinstance(b, (str, bool)):
        return a is b or (type(a) is type(b) and a == b)
    try:
        return bool(np.all(np.asarray(a, dtype=float) == np.asarray(b, dtype=float)))
    except (TypeError, ValueError):
        return False


def _txt(v) -> str:
    import numpy as np

    from .base import BxDF
    if isinstance(v, BxDF):
        return "[" + to_spec(v) + "]"
    if isinstance(v, (np.ndarray, list, tuple)) and not isinstance(v, str):
        a = np.asarray(v, dtype=float).ravel()
        return f"{a[0]:.4g}" if np.all(a == a[0]) else ",".join(f"{x:.4g}" for x in a)
    if isinstance(v, float):
        return f"{v:.4g}"
    if v is None:
        return "none"
    return str(v)


def to_spec(model) -> str:
    """A spec with the parameters of ``model`` that differ from its constructor's defaults
    (informative: conductors show eta and k, not the metal's name)."""
    defaults = {p.name: p.default for p in _params(type(model).__init__)}
    params = dict(model._params)
    if "alpha_x" in params and "alpha_y" in params and _same(params["alpha_x"], params["alpha_y"]):
        params = {("alpha" if k == "alpha_x" else k): v for k, v in params.items() if k != "alpha_y"}
    words = [_snake(type(model).__name__)]
    for k, v in params.items():
        d = defaults.get(k, inspect.Parameter.empty)
        if _same(v, d):   # a None differing from its default is written "none" (Hair's h=None)
            continue
        words.append(f"{k}={_txt(v)}")
    return " ".join(words)
