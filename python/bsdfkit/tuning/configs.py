"""Knobs: each model's accuracy settings, the configurations they span and the model each one builds."""
from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from ..models import BxDF
from ..models import _spectral as _sp

__all__ = ["Knob", "family", "Config", "configurations", "knobs", "COLOR_SETTINGS", "has_spectral_params"]


_DTYPES = {"float64": np.float64, "float32": np.float32}


@dataclass(frozen=True)
class Knob:
    """One accuracy knob of a model instance (made by :func:`knobs`).

    Attributes
    ----------
    name : str
        The knob (a constructor keyword of the model, ``"precision"``, or a lobe name).
    kind : {"approximation", "modelling"}
        A cheaper way to compute the same material (precision, Fresnel approximations, table
        sizes, dropping a negligible lobe) or which material it is (masking, Lambert vs Burley,
        ...), as the model class declares it.
    settings : tuple
        Values, most accurate first.
    labels : tuple of str
        The same as short strings.
    value : object
        The model's current setting (``None`` for precision, which belongs to the call).
    reachable : bool
        False when the knob cannot change the result of this instance in any configuration (then
        ``note`` says why).
    note : str
        What it does, or why it is moot.
    lobe : bool
        True for a keep/drop knob of an optional lobe.
    """

    name: str
    kind: str
    settings: tuple
    labels: tuple
    value: object
    reachable: bool
    note: str
    lobe: bool = False


@dataclass(frozen=True)
class _Spec:
    name: str
    kind: str
    settings: tuple          # values, most accurate first
    labels: tuple
    value: object            # the instance's current value (label space: index into settings)
    moot: object             # callable(params) -> str | None (reason)
    note: str
    param: str | None = None  # the constructor keyword it sets (None: precision)
    lobe: bool = False


def _never(_p):
    return None


def _label(v) -> str:
    if isinstance(v, np.ndarray):
        return "[" + ", ".join(f"{x:.6g}" for x in v) + "]"
    return str(v)


def _precision_spec():
    return _Spec("precision", "approximation", ("float64", "float32"), ("float64", "float32"), None, _never,
                 "kernel precision: float32 directions run float32 kernels (a property of the call)")


#: Settings of the ``color`` knob, most accurate first: spectral mode (``wavelengths=``, the
#: model's spectra per wavelength, integrated to linear sRGB under D65) or RGB mode (spectra
#: projected to linear sRGB once, at construction).
COLOR_SETTINGS = ("spectral", "rgb")


def has_spectral_params(p) -> bool:
    """A parameter set with a non-constant ``bsdfkit.Spectrum``: the models the ``color`` knob applies to."""
    from ..spectral.spectrum import Spectrum
    return any(isinstance(v, Spectrum) and not v.is_constant for v in p.values())


def _color_spec(model):
    """The ``color`` knob (an approximation; a property of the call like precision): present only
    for a model with a non-constant spectral parameter; moot in configurations without a spectral
    kernel (e.g. the stochastic coated models)."""
    cls = type(model)

    def moot(q):
        ok = cls in _sp.spectral_classes() and getattr(cls, "_spectral_ok", lambda _q: True)(q)
        return None if ok else "no spectral kernel for this configuration (wavelengths= not implemented)"
    return _Spec("color", "approximation", COLOR_SETTINGS, COLOR_SETTINGS, None, moot,
                 "colour: spectral mode (per wavelength, integrated to linear sRGB under D65) or RGB mode "
                 "(spectra projected once); a property of the call")


def _spec_of(decl, p, fixed: bool) -> _Spec:
    """The instance form of a class's KnobDecl; ``fixed``: only the input's own setting."""
    settings = tuple(decl.settings(p)) if callable(decl.settings) else tuple(decl.settings)
    labels = tuple(decl.labels(p)) if decl.labels else tuple(_label(v) for v in settings)
    moot = decl.moot or _never
    if decl.lobe:   # a lobe knob is moot when the input has no such lobe (one setting: keep)
        moot = _never if len(settings) > 1 else (lambda q, n=decl.name: f"no {n.replace('_', ' ')}")
    value = p[decl.keyword]
    if fixed:
        i = _index_of(settings, value)
        settings, labels = (settings[i],), (labels[i],)
    return _Spec(decl.name, decl.kind, settings, labels, value, moot, decl.note, decl.keyword, decl.lobe)


def _index_of(settings, value) -> int:
    for i, v in enumerate(settings):
        if np.array_equal(np.asarray(v), np.asarray(value)):
            return i
    return 0


def _check_allow(model, allow) -> frozenset:
    """The modelling knobs named in ``allow`` (validated against the class's declarations)."""
    if allow is None:
        return frozenset()
    if isinstance(allow, str):
        allow = (allow,)
    names = {k.name for k in type(model).knobs if k.kind == "modelling"}
    for a in allow:
        if a not in names:
            raise ValueError(f"allow: {a!r} is not a modelling knob of {type(model).__name__} "
                             f"(its modelling knobs: {', '.join(sorted(names)) or 'none'})")
    return frozenset(allow)


def _specs(model, allow="all") -> list:
    """The knobs of ``model`` as _Spec, precision last. ``allow``: ``"all"`` enumerates every knob
    (tradeoff); a set of names enumerates the approximations and only those modelling knobs, the
    other modelling knobs keeping the input's setting (simplify)."""
    p = model._params
    out = []
    for d in type(model).knobs:
        fixed = allow != "all" and d.kind == "modelling" and d.name not in allow
        out.append(_spec_of(d, p, fixed))
    out.append(_precision_spec())
    if has_spectral_params(p):
        out.append(_color_spec(model))
    return out


def _check_model(model, name="model"):
    if not isinstance(model, BxDF):
        raise TypeError(f"{name}: expected a bsdfkit model (a bsdfkit.BxDF such as bsdfkit.Conductor), "
                        f"got {type(model).__name__}")
    model._refuse_varying("tradeoff / simplify (measure one uniform material)")
    return model


def family(model) -> str:
    """Cost-table family of a model: the class plus the structural variant that selects a different
    compiled kernel (``model.cost_family()``: smooth/rough, Filament's coat/sheen lobes).

    Parameters
    ----------
    model : BxDF
        The model.

    Returns
    -------
    str
        The family name.

    Examples
    --------
    >>> import bsdfkit as bk
    >>> bk.tuning.family(bk.Conductor.from_metal("Cu")), bk.tuning.family(bk.Conductor.from_metal("Cu", alpha=0.3))
    ('Conductor/smooth', 'Conductor/rough')
    """
    _check_model(model)
    return model.cost_family()


@dataclass(frozen=True, eq=False)
class Config:
    """One reachable knob configuration of a model (made by :func:`configurations`).

    Attributes
    ----------
    labels : dict
        ``{knob: label}`` for every registry knob, ``None`` where the knob is moot in this
        configuration.
    index : dict
        Setting index per knob (0 = most accurate; moot knobs 0).
    model : BxDF
        The configured model (moot knobs keep the user's values).
    dtype : type
        ``np.float64`` or ``np.float32``.
    key : str
        The cost-table key (moot knobs at their reference label).
    cheapness : tuple
        Per knob: setting index / (settings - 1), 1 where moot (ranks equally costly
        configurations).
    """

    labels: dict
    index: dict
    model: BxDF
    dtype: type
    key: str
    cheapness: tuple = ()   # per knob: index / (settings - 1), 1 where moot (a moot knob costs nothing)

    @property
    def spectral(self) -> bool:
        """True when this configuration is evaluated in spectral mode (the ``color`` knob)."""
        return self.labels.get("color") == "spectral"

    @property
    def is_reference(self) -> bool:
        return all(v == 0 for v in self.index.values())

    def changes(self) -> dict:
        """The knobs not at their most accurate setting: ``{knob: label}``."""
        return {k: self.labels[k] for k, i in self.index.items() if i > 0}

    def describe(self) -> str:
        ch = self.changes()
        return "most accurate" if not ch else ", ".join(f"{k}={v}" for k, v in ch.items())

    @property
    def registry_rank(self) -> tuple:
        """Sort key of the registry order, cheapest first: the most knobs at (or towards) their
        cheapest setting first (each knob weighs 1 at its cheapest setting or when moot), then
        the later knobs in the registry cheaper first."""
        return (-sum(self.cheapness), tuple(-c for c in reversed(self.cheapness)))


def _apply(model, specs, combo):
    """Configured params for a combination of setting indices, and the moot knobs there."""
    params = dict(model._params)
    for s, i in zip(specs, combo):
        if s.param is not None:
            params[s.param] = s.settings[i]
    moot = {s.name: s.moot(params) for s in specs}
    for s in specs:  # moot knobs keep the user's value
        if moot[s.name] is not None and s.param is not None:
            params[s.param] = model._params[s.param]
    return params, moot


def configurations(model, allow="all") -> list:
    """Every reachable configuration of ``model``, the most accurate first, then in registry order
    of enumeration (later knobs vary fastest).

    Parameters
    ----------
    model : BxDF
        A registered model.
    allow : "all" or tuple of str, optional
        ``"all"`` (default) varies every knob; a tuple of modelling-knob names varies the
        approximation knobs and only those modelling knobs (the others keep the input's setting),
        as :func:`simplify`.

    Returns
    -------
    list of Config
        The configurations.

    Examples
    --------
    >>> import bsdfkit as bk
    >>> cs = bk.tuning.configurations(bk.Conductor.from_metal("Cu", alpha=0.3))
    >>> cs[0].labels
    {'fresnel': 'exact', 'masking': 'correlated', 'distribution': 'ggx', 'precision': 'float64'}
    """
    _check_model(model)
    specs = _specs(model, allow)
    seen, out = set(), []
    for combo in itertools.product(*[range(len(s.settings)) for s in specs]):
        params, moot = _apply(model, specs, combo)
        index = {s.name: (0 if moot[s.name] else i) for s, i in zip(specs, combo)}
        sig = tuple(index.values())
        if sig in seen:
            continue
        seen.add(sig)
        labels = {s.name: (None if moot[s.name] else s.labels[index[s.name]]) for s in specs}
        key = _key(specs, index, moot)
        cheap = tuple(1.0 if moot[s.name] else index[s.name] / max(1, len(s.settings) - 1) for s in specs)
        m = type(model)._from_params(params)
        out.append(Config(labels, index, m, _DTYPES[labels["precision"]], key, cheap))
    return out


def _key(specs, index, moot) -> str:
    """The cost-table key: every knob at its label (moot knobs at their reference label), except
    ``color``, which adds ``;color=spectral`` only in spectral mode (an RGB-mode key is the key of
    the same configuration of a model without spectra: the cost table's)."""
    key = ";".join(f"{s.name}={s.labels[index[s.name]]}" for s in specs if s.name != "color")
    if any(s.name == "color" and not moot[s.name] and index[s.name] == 0 for s in specs):
        key += ";color=spectral"
    return key


def _reference_config(model, allow="all") -> Config:
    specs = _specs(model, allow)
    params, moot = _apply(model, specs, (0,) * len(specs))
    labels = {s.name: (None if moot[s.name] else s.labels[0]) for s in specs}
    key = _key(specs, {s.name: 0 for s in specs}, moot)
    return Config(labels, {s.name: 0 for s in specs}, type(model)._from_params(params), np.float64, key)


def knobs(model) -> tuple:
    """The accuracy knobs of a model instance (tuple of :class:`Knob`), in the order the class
    declares them, precision last. ``reachable`` is False for knobs that cannot change this
    instance's result in any configuration.

    Parameters
    ----------
    model : BxDF
        A registered model.

    Returns
    -------
    tuple of Knob
        The knobs, precision last.

    Examples
    --------
    >>> import bsdfkit as bk
    >>> [(k.name, k.reachable) for k in bk.knobs(bk.Conductor.from_metal("Cu"))]
    [('fresnel', True), ('masking', False), ('distribution', False), ('precision', True)]
    """
    _check_model(model)
    return _knobs_from(model, configurations(model))


def _knobs_from(model, cfgs) -> tuple:
    specs = _specs(model)
    out = []
    for s in specs:
        reach = any(c.index[s.name] > 0 for c in cfgs)
        if reach:
            note = s.note
        else:
            _, moot = _apply(model, specs, (0,) * len(specs))
            note = moot[s.name] or ("only one setting" if len(s.settings) == 1 else s.note)
        out.append(Knob(s.name, s.kind, s.settings, s.labels, s.value, reach, note, s.lobe))
    return tuple(out)
