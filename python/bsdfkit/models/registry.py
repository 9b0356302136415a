"""The model registry: every model class declares itself, everything else reads this.

A subclass of :class:`bsdfkit.BxDF` is registered when it is defined (Mitsuba's
``MI_EXPORT_PLUGIN`` is the pattern), from class attributes it declares:

``aliases``            short names the spec parser accepts besides the class name
``examples``           ``{label: spec}``: representative instances as CLI specs (the first one is
                       the gallery's row); the contract suite runs every one of them
``description``        one line
``knobs``              :class:`KnobDecl` tuple: accuracy settings, each of kind ``"approximation"``
                       (a cheaper way to compute the same material; ``simplify`` may move it) or
                       ``"modelling"`` (which material it is; never changed unless asked)
capability flags       ``energy_conserving``, ``reciprocal`` (f(wo, wi) = f(wi, wo), up to the
                       adjoint for transmission), ``exact_eval`` (False for stochastic models:
                       eval is an estimate), ``two_sided``, ``transmission``, ``delta_only`` (every lobe is a
                       delta: eval and pdf are 0), ``mitsuba`` (the Mitsuba 3 plugin it maps to, or None)
``cost_family()``      (a method) the cost-table family of an instance

Pass ``register=False`` in the class statement (``class Mine(bk.BxDF, register=False)``) for a
class that must not be listed (a test double, an abstract intermediate).
"""
from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Callable

__all__ = ["KnobDecl", "KINDS", "register", "classes", "lookup", "examples", "MODELS", "FLAGS"]

#: Knob kinds: approximations may change in ``simplify``, modelling choices only when allowed.
KINDS = ("approximation", "modelling")
#: Capability flags every registered class declares (all booleans except ``mitsuba``).
FLAGS = ("energy_conserving", "exact_eval", "reciprocal", "two_sided", "transmission", "delta_only", "mitsuba")


@dataclass(frozen=True)
class KnobDecl:
    """An accuracy knob declared by a model class.

    Parameters
    ----------
    name : str
        The knob's name (also the constructor keyword it sets, unless ``param`` says otherwise).
    settings : tuple or callable
        Values, most accurate first, or ``callable(params) -> tuple`` for instance-dependent
        settings (a lobe's ``(strength, 0)``, the DFG sizes around the input's own).
    kind : {"approximation", "modelling"}
        Whether a setting changes accuracy or which material it is.
    note : str
        What it does, one line.
    moot : callable, optional
        ``callable(params) -> str | None``, the reason the knob cannot change this instance
        (``None``: it can).
    param : str, optional
        The constructor keyword, when it is not ``name``.
    labels : callable, optional
        ``callable(params) -> tuple`` of short strings for the settings (default ``str`` of each).
    lobe : bool, optional
        True for "keep/drop a lobe" knobs (simplify prefers dropping a lobe among equally cheap
        configurations).

    Examples
    --------
    >>> import bsdfkit as bk
    >>> [k.name for k in bk.Conductor.knobs]
    ['fresnel', 'masking', 'distribution']
    """

    name: str
    settings: object
    kind: str
    note: str
    moot: Callable | None = None
    param: str | None = None
    labels: Callable | None = None
    lobe: bool = False

    def __post_init__(self):
        if self.kind not in KINDS:
            raise ValueError(f"knob {self.name!r}: kind must be one of {KINDS}, got {self.kind!r}")

    @property
    def keyword(self) -> str:
        return self.param or self.name


_CLASSES: dict = {}   # class name -> class, in registration (gallery) order


def _snake(name: str) -> str:
    return re.sub(r"(?<=[a-z0-9])(?=[A-Z])", "_", name).lower()


def _check_declarations(cls) -> None:
    where = f"{cls.__module__}.{cls.__qualname__}"
    ex = cls.__dict__.get("examples")
    if not isinstance(ex, dict) or not ex or not all(isinstance(k, str) and isinstance(v, str) for k, v in ex.items()):
        raise TypeError(f"{where}: a registered model declares examples = {{label: spec, ...}} (at least one; "
                        f"the first is its gallery row); pass register=False to leave it out of the registry")
    snake = _snake(cls.__name__)
    names = {snake.replace("_", "")} | {a.replace("_", "") for a in cls.aliases}
    for label, spec in ex.items():
        head = spec.split()[0].lower().replace("_", "") if spec.split() else ""
        if head not in names:
            raise TypeError(f"{where}: example {label!r} = {spec!r} must start with {snake!r} or an alias")
    for flag in FLAGS:
        if not hasattr(cls, flag):
            raise TypeError(f"{where}: a registered model declares the capability flag {flag!r}")
    for k in cls.knobs:
        if not isinstance(k, KnobDecl):
            raise TypeError(f"{where}: knobs must be KnobDecl, got {k!r}")
    if not isinstance(cls.description, str) or not cls.description:
        raise TypeError(f"{where}: a registered model declares a one-line description")


def register(cls) -> type:
    """Add a model class to the registry (``BxDF.__init_subclass__`` calls it). Redefining a
    class of the same module and name (a notebook re-run, a reload) replaces the entry."""
    _check_declarations(cls)
    old = _CLASSES.get(cls.__name__)
    if old is not None and (old.__module__, old.__qualname__) != (cls.__module__, cls.__qualname__):
        raise TypeError(f"model name {cls.__name__!r} is already registered by {old.__module__}.{old.__qualname__}")
    taken = {a: c for c in _CLASSES.values() if c.__name__ != cls.__name__ for a in c.aliases}
    for a in cls.aliases:
        if a in taken:
            raise TypeError(f"{cls.__name__}: alias {a!r} is already used by {taken[a].__name__}")
    _CLASSES[cls.__name__] = cls
    return cls


def classes() -> tuple:
    """Every registered model class, in registration (gallery) order."""
    return tuple(_CLASSES.values())


def lookup(name: str):
    """The class named ``name`` (class name, snake_case name or alias; case and ``_``/``-``
    insensitive), or None."""
    key = name.lower().replace("_", "").replace("-", "")
    for cls in _CLASSES.values():
        if key in {cls.__name__.lower()} | {a.lower().replace("_", "") for a in cls.aliases}:
            return cls
    return None


def examples() -> list:
    """``[(cls, label, spec), ...]`` of every registered class, registry order."""
    return [(cls, label, spec) for cls in _CLASSES.values() for label, spec in cls.examples.items()]


class _Models(Sequence):
    """The registered model classes as a live, read-only sequence (``bsdfkit.MODELS``)."""

    def __getitem__(self, i):
        return classes()[i]

    def __len__(self):
        return len(_CLASSES)

    def __add__(self, other):
        return classes() + tuple(other)

    def __eq__(self, other):
        return tuple(self) == tuple(other) if isinstance(other, (Sequence, _Models)) else NotImplemented

    __hash__ = None

    def __repr__(self):
        return "MODELS(" + ", ".join(c.__name__ for c in classes()) + ")"


#: Every registered model class, in gallery order (a live view of the registry).
MODELS = _Models()
