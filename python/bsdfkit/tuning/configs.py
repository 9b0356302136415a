"""Knobs: each model's accuracy settings, the configurations they span and the model each one builds."""
from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from ..models import FilamentCloth, FilamentStandard
from ..models import BxDF, Conductor, Dielectric

__all__ = ["Knob", "family", "Config", "configurations", "knobs"]


_DTYPES = {"float64": np.float64, "float32": np.float32}


@dataclass(frozen=True)
class Knob:
    """One accuracy knob of a model instance.

    name: the knob (a constructor keyword of the model, ``"precision"``, or a lobe name).
    kind: ``"precision"`` | ``"approximation"`` | ``"lobe"``. settings: values, most accurate
    first; labels: the same as short strings. value: the model's current setting (``None`` for
    precision, which belongs to the call). reachable: False when the knob cannot change the
    result of this instance in any configuration (then ``note`` says why).
    """

    name: str
    kind: str
    settings: tuple
    labels: tuple
    value: object
    reachable: bool
    note: str


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


def _never(_p):
    return None


def _label(v) -> str:
    if isinstance(v, np.ndarray):
        return "[" + ", ".join(f"{x:.6g}" for x in v) + "]"
    return str(v)


def _choice_spec(p, name, order, moot, note):
    return _Spec(name, "approximation", tuple(order), tuple(_label(v) for v in order), p[name], moot, note, name)


def _precision_spec():
    return _Spec("precision", "precision", ("float64", "float32"), ("float64", "float32"), None, _never,
                 "kernel precision: float32 directions run float32 kernels (a property of the call)")


def _smooth(p) -> bool:
    return max(p["alpha_x"], p["alpha_y"]) < 1e-3


def _conductor_specs(m):
    p = m._params
    return [
        _choice_spec(p, "fresnel", ("exact", "f82", "schlick"), _never,
                     "conductor Fresnel: complex (exact), F82-tint, Schlick"),
        _choice_spec(p, "masking", ("correlated", "separable"),
                     lambda q: "smooth conductor (max alpha < 1e-3): a mirror has no masking" if _smooth(q) else None,
                     "Smith masking-shadowing: height-correlated or separable G1 G1"),
        _precision_spec()]


def _dielectric_specs(m):
    p = m._params

    def moot(q):
        if _smooth(q):
            return "smooth dielectric (max alpha < 1e-3): delta lobes have no masking"
        if q["eta"] == 1.0:
            return "eta = 1: light passes straight through, no microfacets involved"
        return None
    return [_choice_spec(p, "masking", ("correlated", "separable"), moot,
                         "Smith masking-shadowing: height-correlated or separable G1 G1"), _precision_spec()]


def _filament_f0(q) -> np.ndarray:
    """Per-channel f0 of a FilamentStandard parameter set (computeF0 + CLEAR_COAT_IOR_CHANGE)."""
    from ..models.filament import dfg as _fil
    f0 = q["base_color"] * q["metallic"] + 0.16 * q["reflectance"] ** 2 * (1 - q["metallic"])
    if q["clear_coat_ior_change"] and q["clear_coat"] > 0:
        cc = q["clear_coat"]
        f0 = f0 + cc * (_fil.term("f0ClearCoatToSurface", f0) - f0)
    return f0


def _lut_settings(v: int) -> tuple:
    """DFG table sizes, largest (most accurate) first: 128, 64, 32, 16 and the input's own size."""
    return tuple(sorted({128, 64, 32, 16, int(v)}, reverse=True))


def _filament_standard_specs(m):
    p = m._params
    cc, sheen = p["clear_coat"], p["sheen_color"]

    def diffuse_moot(q):
        return ("no diffuse colour (base_color (1 - metallic) = 0)"
                if float(np.max(q["base_color"] * (1 - q["metallic"]))) == 0 else None)

    def vis_moot(q):
        return "anisotropic lobe: always V_SmithGGXCorrelated_Anisotropic" if q["anisotropy"] != 0 else None

    def f90_moot(q):
        return ("the f90 rule saturates (16.5 sum(f0) >= 1): f90 = 1 either way"
                if 16.5 * float(np.sum(_filament_f0(q))) >= 1.0 else None)

    def ec_moot(q):
        return "f0 = 0: the compensation 1 + f0 (1/DFG.y - 1) is 1" if float(np.max(_filament_f0(q))) == 0 else None

    def lut_moot(q):
        ec_on = q["energy_compensation"] and ec_moot(q) is None
        has_sheen = float(np.max(q["sheen_color"])) > 0
        if not ec_on and not has_sheen:
            return "without energy compensation and sheen, the DFG table only feeds sampling probabilities"
        return None

    specs = []
    specs.append(_Spec("clear_coat", "lobe", (cc, 0.0) if cc > 0 else (cc,), ("keep", "drop") if cc > 0 else ("keep",),
                       cc, lambda q: None if cc > 0 else "no clear coat",
                       "clear-coat lobe: keep, or drop (clear_coat = 0, compiled variant without the coat)",
                       "clear_coat"))
    has_sheen = float(np.max(sheen)) > 0
    specs.append(_Spec("sheen", "lobe", (sheen, np.zeros(3)) if has_sheen else (sheen,),
                       ("keep", "drop") if has_sheen else ("keep",), sheen,
                       lambda q: None if has_sheen else "no sheen",
                       "sheen lobe: keep, or drop (sheen_color = 0, compiled variant without sheen)", "sheen_color"))
    specs.append(_choice_spec(p, "diffuse", ("burley", "lambert"), diffuse_moot,
                              "diffuse term: Fd_Burley (retro-reflection, grazing falloff) or Fd_Lambert"))
    specs.append(_choice_spec(p, "visibility", ("correlated", "fast"), vis_moot,
                              "V_SmithGGXCorrelated or its _Fast approximation (Hammon 2017)"))
    specs.append(_choice_spec(p, "f90", ("filament", "one"), f90_moot,
                              "Schlick f90: the specular-occlusion rule saturate(16.5 sum f0), or 1"))
    specs.append(_choice_spec(p, "energy_compensation", (True, False), ec_moot,
                              "multiple-scattering energy compensation 1 + f0 (1/DFG.y - 1)"))
    specs.append(_choice_spec(p, "dfg_lut_size", _lut_settings(p["dfg_lut_size"]), lut_moot,
                              "side of the DFG table (energy compensation, sheen scaling)"))
    specs.append(_precision_spec())
    return specs


def _filament_cloth_specs(m):
    p = m._params
    return [
        _choice_spec(p, "diffuse", ("burley", "lambert"),
                     lambda q: "black base colour" if float(np.max(q["base_color"])) == 0 else None,
                     "diffuse term: Fd_Burley or Fd_Lambert"),
        _choice_spec(p, "dfg_lut_size", (p["dfg_lut_size"],),
                     lambda q: "the cloth's DFG table only feeds the lobe-selection probabilities of sample/pdf",
                     "side of the DFG table (sampling probabilities only)"),
        _precision_spec()]


def _specs(model) -> list:
    if isinstance(model, Conductor):
        return _conductor_specs(model)
    if isinstance(model, Dielectric):
        return _dielectric_specs(model)
    if isinstance(model, FilamentStandard):
        return _filament_standard_specs(model)
    if isinstance(model, FilamentCloth):
        return _filament_cloth_specs(model)
    return [_precision_spec()]   # Diffuse, DiffuseTransmission, ThinDielectric, any later model


def _check_model(model, name="model"):
    if not isinstance(model, BxDF):
        raise TypeError(f"{name}: expected a bsdfkit model (a bsdfkit.BxDF such as bsdfkit.Conductor), "
                        f"got {type(model).__name__}")
    return model


def family(model) -> str:
    """Cost-table family of a model: the class plus the structural variant that selects a
    different compiled kernel (smooth/rough, Filament's coat/sheen lobes)."""
    _check_model(model)
    p = model._params
    name = type(model).__name__
    if isinstance(model, Conductor):
        return name + ("/smooth" if _smooth(p) else "/rough")
    if isinstance(model, Dielectric):
        return name + ("/smooth" if _smooth(p) or p["eta"] == 1.0 else "/rough")
    if isinstance(model, FilamentStandard):
        lobes = [x for x, on in (("coat", p["clear_coat"] > 0), ("sheen", float(np.max(p["sheen_color"])) > 0)) if on]
        return name + ("/" + "+".join(lobes) if lobes else "")
    return name


@dataclass(frozen=True, eq=False)
class Config:
    """One reachable knob configuration of a model.

    labels: ``{knob: label}`` for every registry knob, ``None`` where the knob is moot in this
    configuration. index: setting index per knob (0 = most accurate; moot knobs 0). model: the
    configured model (moot knobs keep the user's values). dtype: ``np.float64`` or ``np.float32``.
    key: the cost-table key (moot knobs at their reference label).
    """

    labels: dict
    index: dict
    model: BxDF
    dtype: type
    key: str
    cheapness: tuple = ()   # per knob: index / (settings - 1), 1 where moot (a moot knob costs nothing)

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


def configurations(model) -> list:
    """Every reachable configuration of ``model`` (a list of :class:`Config`), the most accurate
    first, then in registry order of enumeration (later knobs vary fastest)."""
    _check_model(model)
    specs = _specs(model)
    seen, out = set(), []
    for combo in itertools.product(*[range(len(s.settings)) for s in specs]):
        params, moot = _apply(model, specs, combo)
        index = {s.name: (0 if moot[s.name] else i) for s, i in zip(specs, combo)}
        sig = tuple(index.values())
        if sig in seen:
            continue
        seen.add(sig)
        labels = {s.name: (None if moot[s.name] else s.labels[index[s.name]]) for s in specs}
        key = ";".join(f"{s.name}={s.labels[index[s.name]]}" for s in specs)
        cheap = tuple(1.0 if moot[s.name] else index[s.name] / max(1, len(s.settings) - 1) for s in specs)
        m = type(model)._from_params(params)
        out.append(Config(labels, index, m, _DTYPES[labels["precision"]], key, cheap))
    return out


def _reference_config(model) -> Config:
    specs = _specs(model)
    params, moot = _apply(model, specs, (0,) * len(specs))
    labels = {s.name: (None if moot[s.name] else s.labels[0]) for s in specs}
    key = ";".join(f"{s.name}={s.labels[0]}" for s in specs)
    return Config(labels, {s.name: 0 for s in specs}, type(model)._from_params(params), np.float64, key)


def knobs(model) -> tuple:
    """The accuracy knobs of a model instance (tuple of :class:`Knob`), registry order: lobes,
    approximations, precision last. ``reachable`` is False for knobs that cannot change this
    instance's result in any configuration."""
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
        out.append(Knob(s.name, s.kind, s.settings, s.labels, s.value, reach, note))
    return tuple(out)
