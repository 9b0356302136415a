"""Speed versus accuracy: the knob registry, :func:`tradeoff`, :func:`simplify` and :func:`pareto`.

Every approximation in bsdfkit is a *knob* of a model: one code path with the setting as a
parameter, never a copied model variant. :func:`knobs` lists the knobs of a model instance,
each with its settings ordered from the most accurate to the cheapest:

===================  ==============================================  =====================================
model                knob (most accurate -> cheapest)                 moot (not an accuracy choice) when
===================  ==============================================  =====================================
every model          precision: float64 -> float32                    never (a property of the call: float32
                                                                      directions run float32 kernels)
Conductor            fresnel: exact -> f82 -> schlick                 never
                     masking: correlated -> separable                 smooth (max alpha < 1e-3: a mirror)
Dielectric           masking: correlated -> separable                 smooth, or eta == 1
FilamentStandard     clear_coat (lobe): keep -> drop (0)              clear_coat == 0
                     sheen (lobe): keep -> drop (sheen_color 0)       sheen_color == 0
                     diffuse: burley -> lambert                       no diffuse colour (metallic 1 / black)
                     visibility: correlated -> fast                   anisotropy != 0 (always anisotropic V)
                     f90: filament -> one                             16.5 sum(f0) >= 1 (the rule gives 1)
                     energy_compensation: True -> False               f0 == 0
                     dfg_lut_size: 128 -> 64 -> 32 -> 16              energy compensation off and no sheen
FilamentCloth        diffuse: burley -> lambert                       black base colour
                     dfg_lut_size                                     always: only lobe selection uses it
===================  ==============================================  =====================================

Why these orders: Lambert is Burley's diffuse with its retro-reflection / grazing term switched
off (``Fd_Burley`` with f90 = 1 *is* ``Fd_Lambert``), so Burley, which reproduces the roughness-
dependent diffuse falloff Burley 2012 fitted to measured (MERL) materials, is treated as the more
accurate one, although Filament defaults to Lambert. ``f90 = 1`` is the "filament" rule without
its specular-occlusion clamp for f0 below 2 %; energy compensation off drops the multiple-
scattering term; smaller DFG tables interpolate coarser. Knobs that change *which* material is
modelled rather than how accurately (``min_roughness``, ``clear_coat_layering``,
``clear_coat_ior_change``, Filament cloth's ``subsurface_color``, every physical parameter) are not
knobs here: the user's value is kept. The cloth's DFG table only feeds the lobe-selection
probabilities of ``sample``/``pdf`` (sampling efficiency, not f or the albedo), so it is never an
accuracy knob. Lobe knobs drop a lobe (strength 0): the model then also gets the compiled variant
without that lobe. A knob is *reachable* in a configuration unless it is moot there; a moot knob
keeps the user's value and configurations that differ only in moot knobs are one configuration.

Error definition (used by :func:`tradeoff`, :func:`simplify`, the tests and ``bench/tradeoff.py``):

* values compared: ``v = f(wo, wi) |cos theta_i|`` per direction pair and RGB channel, the cosine
  of the float64 ``wi``; a float32 configuration is run on float32 copies of the directions
  (and uniforms), because precision is a property of the call in bsdfkit.
* relative error per pair and channel: ``|v_cfg - v_ref| / max(|v_ref|, floor)`` with
  ``floor = 1e-3 * mean(albedo_ref) / pi``: relative where the reference is brighter than a
  thousandth of a Lambertian surface of the material's mean directional albedo, absolute in those
  units below it. A floor taken from the set itself (``1e-3 max|v_ref|``) would be set by the
  highlight peak of a glossy lobe (1e4 and more for alpha ~ 0.01) and hide every error off the
  peak; this one depends only on how much light the material reflects, not on how peaked it is
  nor on how the direction set was drawn. ``Table.floor`` holds the value used.
* ``max_err`` and ``p99_err``: the maximum and numpy's default (linear) 0.99-quantile of that
  relative error over every pair and channel of the direction set.
* ``albedo_err``: ``max |albedo_cfg(wo) - albedo_ref(wo)|`` over channels and the albedo set of
  wo (cos theta_o = 1, 0.7, 0.4, 0.15, 0.05, 0.01, also below the surface for transmissive
  models). Both albedos are estimated from the *same* importance samples of the reference
  configuration (``f_cfg |cos| / pdf_ref``; stratified uniforms, common to all configurations), so
  their difference is estimated with an error proportional to the difference itself, far below
  the tolerances (an independent Monte Carlo estimate per configuration would need ~1e8 samples
  for 1e-4).
* delta (specular) lobes: ``eval`` is 0 for every given pair, so such lobes are compared on
  sampled pairs: each configuration is sampled with the same ``(wo, uc, u)`` as the reference and
  ``v = f |cos theta_i|`` of the sample is compared (a configuration that picks another lobe or
  direction counts as 0 there, i.e. a full error). Models made only of delta lobes are measured
  this way, and their throughput is that of ``sample``.

Default direction set (:func:`direction_set`): half the pairs stratified (Latin hypercube over
cos theta_o, phi_o, cos theta_i, phi_i; cos from 1e-3 to 1, both hemispheres for transmissive
models), half importance-sampled from the most accurate configuration (its highlights and delta
lobes; stratified uniforms at stratified wo). Deterministic for a seed; another seed gives another
set of the same distribution.

Ranking (why :func:`simplify` is deterministic): "fastest" is decided by a *cost table*, not by a
timing taken during the call (noisy, load dependent). ``bench/tradeoff.py`` measures, on this
machine class, the cost of every configuration of one representative per model family relative to
its most accurate configuration, and ships it as package data (``_knob_costs.json``). Among the
configurations within tolerance, those whose cost is within ``COST_RESOLUTION`` (5 %, the table's
measurement resolution) of the cheapest count as equally fast; of those, the one dropping the most
lobes wins (a lobe within tolerance is removed even where its cost is in the noise: the material
gets simpler), then the most accurate (an approximation that buys no measurable speed is not
taken). A configuration missing from the
table is assumed to cost as much as the most accurate one; a family missing altogether is ranked
by registry order alone (the configuration with the most knobs at their cheapest settings).
:func:`simplify` reports the speedup that table predicts; :func:`tradeoff` shows next to it the
live measurement of its own run (ratios to the most accurate configuration timed back to back,
best of ``repeats``). The table is per-element cost measured single-threaded (bench/TRADEOFF.md):
what the knobs change is arithmetic per direction, which threads do not change.
"""
from __future__ import annotations

import html as _html
import itertools
import json
import math
import numbers
import os
import time
from dataclasses import dataclass, field

import numpy as np

from ._enums import BxDFFlags
from ._filament_models import FilamentCloth, FilamentStandard
from ._models import BxDF, Conductor, Dielectric

__all__ = ["Knob", "knobs", "Config", "configurations", "DirectionSet", "direction_set", "tradeoff", "simplify",
           "Table", "SimplifyReport", "pareto", "relative_error", "knob_costs", "family", "METRICS", "FLOOR_FRACTION",
           "ALBEDO_COS_THETA", "COST_RESOLUTION"]

#: Error metrics accepted by :func:`simplify` and :func:`pareto`, and their Table columns.
METRICS = {"max": "max_err", "p99": "p99_err", "albedo": "albedo_err"}
#: floor = FLOOR_FRACTION * mean(albedo_ref) / pi (see the module docstring).
FLOOR_FRACTION = 1e-3
#: cos theta_o of the directional-albedo set (mirrored below the surface for transmissive models).
ALBEDO_COS_THETA = (1.0, 0.7, 0.4, 0.15, 0.05, 0.01)
#: Smallest |cos theta| of the default direction set.
MIN_COS = 1e-3
_DTYPES = {"float64": np.float64, "float32": np.float32}


# ============================================================================ knob registry

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
    from . import filament as _fil
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
    if name == "Hair" and p.get("h", 0.0) is None:
        return name + "/far-field"   # 16 single-h kernels per call
    return name


# ============================================================================ configurations

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


# ============================================================================ direction sets

def _lhs(rng, n: int, d: int) -> np.ndarray:
    """Latin hypercube: (n, d), every column stratified into n equal strata."""
    perm = np.argsort(rng.random((d, n)), axis=1).T
    return (perm + rng.random((n, d))) / n


def _dirs(mu, phi):
    s = np.sqrt(np.maximum(0.0, 1.0 - mu * mu))
    return np.stack([s * np.cos(phi), s * np.sin(phi), mu], axis=-1)


def _is_transmissive(model) -> bool:
    return bool(model.flags & BxDFFlags.Transmission)


def _all_delta(model) -> bool:
    f = model.flags
    return bool(f & BxDFFlags.Specular) and not (f & (BxDFFlags.Diffuse | BxDFFlags.Glossy))


@dataclass(frozen=True, eq=False)
class DirectionSet:
    """The directions every configuration is compared on (float64 arrays).

    wo, wi: (N, 3) pairs evaluated with ``eval`` (stratified pairs and the non-delta samples of
    the reference). delta_wo, delta_uc, delta_u: inputs of the delta-lobe rows, where each
    configuration is sampled with the same uniforms. albedo_wo (K, 3), albedo_uc (M,),
    albedo_u (M, 2): the directional-albedo set (M samples of the reference per wo). seed: the
    seed it was drawn with (None if given by the user).
    """

    wo: np.ndarray
    wi: np.ndarray
    delta_wo: np.ndarray
    delta_uc: np.ndarray
    delta_u: np.ndarray
    albedo_wo: np.ndarray
    albedo_uc: np.ndarray
    albedo_u: np.ndarray
    seed: int | None = None

    def __len__(self):
        return len(self.wo) + len(self.delta_wo)


def _albedo_inputs(model, rng, n_albedo):
    mu = np.asarray(ALBEDO_COS_THETA)
    phi = 0.3 + 2.399963229728653 * np.arange(len(mu))          # golden-angle azimuths (anisotropy)
    wo = _dirs(mu, phi)
    if _is_transmissive(model):
        below = wo.copy()
        below[:, 2] *= -1
        wo = np.concatenate([wo, below])
    h = _lhs(rng, n_albedo, 3)
    return wo, np.ascontiguousarray(h[:, 0]), np.ascontiguousarray(h[:, 1:])


def direction_set(model, n: int = 8192, seed: int = 0, *, n_albedo: int = 4096) -> DirectionSet:
    """The default direction set of ``model`` (see the module docstring): ``n`` rows, half
    stratified pairs and half samples of the most accurate configuration (all samples for models
    made only of delta lobes), plus the albedo set with ``n_albedo`` samples per wo."""
    _check_model(model)
    n = _check_int(n, "n", 16)
    seed = _check_int(seed, "seed", 0)
    n_albedo = _check_int(n_albedo, "n_albedo", 16)
    rng = np.random.default_rng([seed, 0x7472616465])
    trans = _is_transmissive(model)
    ref = _reference_config(model).model
    n_strat = 0 if _all_delta(model) else n // 2
    h = _lhs(rng, n_strat, 6)
    mu_o = MIN_COS + (1 - MIN_COS) * h[:, 0]
    mu_i = MIN_COS + (1 - MIN_COS) * h[:, 2]
    if trans:   # half of each: wi below, wo below (exactly, by stratification)
        mu_i = np.where(h[:, 4] < 0.5, -mu_i, mu_i)
        mu_o = np.where(h[:, 5] < 0.5, -mu_o, mu_o)
    wo = _dirs(mu_o, 2 * np.pi * h[:, 1])
    wi = _dirs(mu_i, 2 * np.pi * h[:, 3])
    # samples of the reference at stratified wo
    n_samp = n - n_strat
    g = _lhs(rng, n_samp, 6)
    smu = MIN_COS + (1 - MIN_COS) * g[:, 0]
    if trans:
        smu = np.where(g[:, 5] < 0.5, -smu, smu)
    swo = _dirs(smu, 2 * np.pi * g[:, 1])
    suc, su = np.ascontiguousarray(g[:, 2]), np.ascontiguousarray(g[:, 3:5])
    s = ref.sample(swo, suc, su)
    delta = s.valid & ((s.flags & int(BxDFFlags.Specular)) != 0)
    smooth = s.valid & ~delta
    a_wo, a_uc, a_u = _albedo_inputs(model, rng, n_albedo)
    return DirectionSet(wo=np.concatenate([wo, swo[smooth]]), wi=np.concatenate([wi, s.wi[smooth]]),
                        delta_wo=swo[delta], delta_uc=suc[delta], delta_u=su[delta],
                        albedo_wo=a_wo, albedo_uc=a_uc, albedo_u=a_u, seed=seed)


def _user_directions(model, directions, seed, n_albedo) -> DirectionSet:
    if isinstance(directions, DirectionSet):
        return directions
    if not isinstance(directions, (tuple, list)) or len(directions) != 2:
        raise TypeError("directions: expected None, a DirectionSet or a pair (wo, wi) of direction arrays")
    try:
        wo, wi = np.broadcast_arrays(np.asarray(directions[0], dtype=np.float64),
                                     np.asarray(directions[1], dtype=np.float64))
    except (ValueError, TypeError) as e:
        raise ValueError(f"directions: wo and wi must be real arrays that broadcast together ({e})") from None
    if wo.ndim < 1 or wo.shape[-1] != 3 or wo.size == 0:
        raise ValueError(f"directions: expected direction arrays with last axis 3, got shape {wo.shape}")
    wo, wi = wo.reshape(-1, 3).copy(), wi.reshape(-1, 3).copy()
    for a, nm in ((wo, "wo"), (wi, "wi")):
        if not np.all(np.isfinite(a)) or np.any(np.abs(np.einsum("ij,ij->i", a, a) - 1) > 1e-4):
            raise ValueError(f"directions: every {nm} must be a finite unit vector")
    rng = np.random.default_rng([seed, 0x75736572])
    d_wo = np.empty((0, 3))
    d_uc, d_u = np.empty(0), np.empty((0, 2))
    if model.flags & BxDFFlags.Specular:   # delta lobes cannot be evaluated at given pairs: sample them at wo
        g = _lhs(rng, len(wo), 3)
        uc, u = np.ascontiguousarray(g[:, 0]), np.ascontiguousarray(g[:, 1:])
        s = _reference_config(model).model.sample(wo, uc, u)
        delta = s.valid & ((s.flags & int(BxDFFlags.Specular)) != 0)
        d_wo, d_uc, d_u = wo[delta], uc[delta], u[delta]
    a_wo, a_uc, a_u = _albedo_inputs(model, rng, n_albedo)
    return DirectionSet(wo, wi, d_wo, d_uc, d_u, a_wo, a_uc, a_u, None)


# ============================================================================ evaluation

def relative_error(v_ref, v, floor: float) -> np.ndarray:
    """``|v - v_ref| / max(|v_ref|, floor)`` elementwise (float64)."""
    v_ref = np.asarray(v_ref, dtype=np.float64)
    return np.abs(np.asarray(v, dtype=np.float64) - v_ref) / np.maximum(np.abs(v_ref), floor)


class _Prepared:
    """The direction set expanded against the reference: albedo sample rows and their weights."""

    def __init__(self, ref: BxDF, ds: DirectionSet):
        self.ds = ds
        k, m = len(ds.albedo_wo), len(ds.albedo_uc)
        wo = np.repeat(ds.albedo_wo, m, axis=0)
        uc, u = np.tile(ds.albedo_uc, k), np.tile(ds.albedo_u, (k, 1))
        s = ref.sample(wo, uc, u)
        delta = s.valid & ((s.flags & int(BxDFFlags.Specular)) != 0)
        smooth = s.valid & ~delta & (s.pdf > 0)
        self.k, self.m = k, m
        # albedo rows: evaluated pairs (smooth) and re-sampled rows (delta), weight 1 / (pdf m)
        self.a_wo, self.a_wi = wo[smooth], s.wi[smooth]
        self.a_w = 1.0 / (s.pdf[smooth] * m)
        self.a_group = np.repeat(np.arange(k), m)[smooth]
        self.ad_wo, self.ad_uc, self.ad_u = wo[delta], uc[delta], u[delta]
        self.ad_wi, self.ad_flags = s.wi[delta], s.flags[delta]
        self.ad_w = 1.0 / (s.pdf[delta] * m)
        self.ad_group = np.repeat(np.arange(k), m)[delta]
        # delta rows of the error set: the reference's own samples
        if len(ds.delta_wo):
            r = ref.sample(ds.delta_wo, ds.delta_uc, ds.delta_u)
            self.d_wi, self.d_flags = r.wi, r.flags
        else:
            self.d_wi, self.d_flags = np.empty((0, 3)), np.empty(0, np.uint8)


def _eval_cos(m, dtype, wo, wi):
    if len(wo) == 0:
        return np.empty((0, 3))
    f = m.eval(wo.astype(dtype), wi.astype(dtype))
    return f.astype(np.float64) * np.abs(wi[:, 2:3])


def _delta_cos(m, dtype, wo, uc, u, wi_ref, flags_ref):
    if len(wo) == 0:
        return np.empty((0, 3))
    s = m.sample(wo.astype(dtype), uc.astype(dtype), u.astype(dtype))
    wi = s.wi.astype(np.float64)
    same = s.valid & (s.flags == flags_ref) & (np.max(np.abs(wi - wi_ref), axis=1) < 1e-3)
    v = s.f.astype(np.float64) * np.abs(wi[:, 2:3])
    return np.where(same[:, None], v, 0.0)


def _values(cfg: Config, prep: _Prepared):
    """(values on the error set (N, 3), albedo (K, 3)) of one configuration."""
    ds, m, dt = prep.ds, cfg.model, cfg.dtype
    v = np.concatenate([_eval_cos(m, dt, ds.wo, ds.wi),
                        _delta_cos(m, dt, ds.delta_wo, ds.delta_uc, ds.delta_u, prep.d_wi, prep.d_flags)])
    alb = np.zeros((prep.k, 3))
    if len(prep.a_wo):
        np.add.at(alb, prep.a_group, _eval_cos(m, dt, prep.a_wo, prep.a_wi) * prep.a_w[:, None])
    if len(prep.ad_wo):
        vd = _delta_cos(m, dt, prep.ad_wo, prep.ad_uc, prep.ad_u, prep.ad_wi, prep.ad_flags)
        np.add.at(alb, prep.ad_group, vd * prep.ad_w[:, None])
    return v, alb


class _Evaluation:
    """Errors of every configuration of a model against its most accurate one."""

    def __init__(self, model, directions, n, seed, n_albedo):
        self.model = model
        self.configs = configurations(model)
        self.reference = self.configs[0]
        assert self.reference.is_reference
        if directions is None:
            self.directions = direction_set(model, n, seed, n_albedo=n_albedo)
        else:
            self.directions = _user_directions(model, directions, seed, n_albedo)
        prep = _Prepared(self.reference.model, self.directions)
        v_ref, a_ref = _values(self.reference, prep)
        self.reference_albedo = a_ref
        mean_alb = float(np.mean(np.abs(a_ref)))
        self.floor = FLOOR_FRACTION * mean_alb / math.pi if mean_alb > 0 else 1e-30
        self.errors = []
        for c in self.configs:
            v, a = (v_ref, a_ref) if c is self.reference else _values(c, prep)
            e = relative_error(v_ref, v, self.floor)
            self.errors.append({
                "max_err": float(np.max(e)) if e.size else 0.0,
                "p99_err": float(np.quantile(e, 0.99)) if e.size else 0.0,
                "albedo_err": float(np.max(np.abs(a - a_ref))) if a.size else 0.0})


# ============================================================================ costs

_COSTS_CACHE: dict = {}


def knob_costs(path=None) -> dict:
    """The shipped cost table (``bsdfkit/_knob_costs.json``, written by ``bench/tradeoff.py``):
    ``{"families": {family: {"op": ..., "costs": {config key: time / time of the most accurate}}},
    ...}``; ``{}`` when it is missing. ``path`` reads another file (not cached)."""
    if path is None:
        path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "_knob_costs.json")
        if path in _COSTS_CACHE:
            return _COSTS_CACHE[path]
        cache = True
    else:
        cache = False
    try:
        with open(path, encoding="utf-8") as fh:
            data = json.load(fh)
    except FileNotFoundError:
        data = {}
    if cache:
        _COSTS_CACHE[path] = data
    return data


def _check_costs(costs) -> dict:
    if costs is None:
        return knob_costs()
    if not isinstance(costs, dict):
        raise TypeError(f"costs: expected a cost table dict (see knob_costs()), got {type(costs).__name__}")
    return costs


def _costs_for(model, configs, costs):
    table = costs.get("families", {}).get(family(model), {}).get("costs", {})
    return [table.get(c.key) for c in configs]


#: Relative cost differences below this are measurement noise of the cost table: among the
#: candidates within (1 + COST_RESOLUTION) x the cheapest cost, simplify takes the one that drops
#: the most lobes, then the most accurate.
COST_RESOLUTION = 0.05


def _pick(cands, costs, configs, err):
    """Index of the chosen candidate and how it was ranked (see :func:`simplify`)."""
    if all(c is None for c in costs):
        return min(cands, key=lambda i: configs[i].registry_rank), "registry order (no cost table for this family)"
    c = {i: 1.0 if costs[i] is None else float(costs[i]) for i in cands}
    cmin = min(c.values())
    near = [i for i in cands if c[i] <= cmin * (1 + COST_RESOLUTION)]
    drops = {i: sum(v == "drop" for v in configs[i].labels.values()) for i in near}
    best = min(near, key=lambda i: (-drops[i], err[i], configs[i].registry_rank))
    return best, "cost table" + (" (this configuration is missing: assumed as costly as the most accurate)"
                                 if costs[best] is None else "")


# ============================================================================ timing

def best_time(fn, repeats=5, min_time=0.005, warmup=1):
    """Min over ``repeats`` of the mean time of ``inner`` back-to-back calls of ``fn`` after
    ``warmup`` calls; ``inner`` is chosen so that one repeat takes >= ``min_time`` seconds.
    Also the timer of ``bench/throughput.py`` and ``bench/filament.py``."""
    for _ in range(warmup):
        fn()
    t0 = time.perf_counter()
    fn()
    dt = time.perf_counter() - t0
    inner = max(1, int(math.ceil(min_time / max(dt, 1e-9)))) if dt < min_time else 1
    best = math.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(inner):
            fn()
        best = min(best, (time.perf_counter() - t0) / inner)
    return best


def _timing_inputs(model, n, seed):
    rng = np.random.default_rng([seed, 0x74696d65])

    def unit(upper):
        v = rng.standard_normal((n, 3))
        v /= np.linalg.norm(v, axis=1, keepdims=True)
        if upper:
            v[:, 2] = np.abs(v[:, 2])
        return v
    d = {"wo": unit(True), "wi": unit(not _is_transmissive(model)), "uc": rng.random(n), "u": rng.random((n, 2))}
    return {"float64": d, "float32": {k: v.astype(np.float32) for k, v in d.items()}}


def _timed_call(cfg: Config, op: str, inputs):
    d = inputs["float64" if cfg.dtype is np.float64 else "float32"]
    n, dt, m = len(d["wo"]), d["wo"].dtype, cfg.model
    if op == "eval":
        out = np.empty((n, 3), dt)
        return lambda: m.eval(d["wo"], d["wi"], out=out)
    bufs = (np.empty((n, 3), dt), np.empty((n, 3), dt), np.empty(n, dt), np.empty(n, np.uint8), np.empty(n, dt),
            np.empty(n, bool), np.empty(n, bool))
    core = m._core
    return lambda: core.sample(d["wo"], d["uc"], d["u"], 0, 3, *bufs)


def _op(model) -> str:
    return "sample" if _all_delta(model) else "eval"


def _measure(configs, op, n_timing, repeats, rounds, seed):
    """Live throughput: every configuration timed right after the most accurate one (best of
    ``repeats``), in ``rounds`` interleaved rounds; returns (evals/s, speedup) lists, speedup =
    smallest reference time of the run / smallest time of the configuration (a load spike during
    one reference timing then cannot inflate a ratio)."""
    inputs = _timing_inputs(configs[0].model, n_timing, seed)
    calls = [_timed_call(c, op, inputs) for c in configs]
    t_ref, t = math.inf, [math.inf] * len(configs)
    for _ in range(rounds):
        for i, call in enumerate(calls):
            tr = best_time(calls[0], repeats)
            t_ref = min(t_ref, tr)
            t[i] = min(t[i], tr if i == 0 else best_time(call, repeats))
    t[0] = t_ref
    return [n_timing / x for x in t], [t_ref / x for x in t]


# ============================================================================ Table

def _pareto_mask(err, thr) -> np.ndarray:
    """True where no other point has error <= and throughput >= with one of them strict."""
    err, thr = np.asarray(err, float), np.asarray(thr, float)
    mask = np.ones(len(err), bool)
    for i in range(len(err)):
        dom = (err <= err[i]) & (thr >= thr[i]) & ((err < err[i]) | (thr > thr[i]))
        mask[i] = not dom.any()
    return mask


def _fmt_cell(v, col):
    if v is None:
        return "—"
    if isinstance(v, (bool, np.bool_)):
        return "✓" if v else ""
    if col == "evals_per_s":
        return f"{v / 1e6:.1f}M"
    if col in ("speedup", "expected_speedup"):
        return f"{v:.2f}×"
    if isinstance(v, float):
        return "0" if v == 0 else f"{v:.2e}"
    return str(v)


class Table:
    """Result of :func:`tradeoff`: one row per reachable configuration, the most accurate first.

    Columns: ``config`` (what differs from the most accurate configuration), one column per
    reachable knob, ``dtype``, ``op`` (timed operation: eval, or sample for delta-only models),
    ``evals_per_s`` and ``speedup`` (live, this run, ratio to the most accurate configuration
    timed back to back; ``None`` with ``measure=False``), ``expected_speedup`` (from the shipped
    cost table, ``None`` if the configuration is not in it), ``max_err``, ``p99_err``,
    ``albedo_err`` (see the module docstring) and ``pareto`` (on the front of throughput vs
    p99 error; throughput = live speedup, else expected speedup).

    Renders as text (``str``), Markdown and HTML (Jupyter); ``to_records()`` (list of dicts),
    ``to_dict()`` (dict of columns) and ``to_pandas()`` (needs pandas). ``table[i]`` is a row,
    ``table["p99_err"]`` a column, ``table.configs[i]`` the :class:`Config` (``.model``,
    ``.dtype``). Attributes: model, reference (the most accurate model), knobs, floor,
    reference_albedo, directions (the :class:`DirectionSet`), seed, family, measured.
    """

    def __init__(self, model, evaluation: _Evaluation, rates, speedups, expected, info):
        self.model = model
        self.configs = evaluation.configs
        self.reference = evaluation.reference.model
        self.knobs = _knobs_from(model, self.configs)
        self.floor = evaluation.floor
        self.reference_albedo = evaluation.reference_albedo
        self.directions = evaluation.directions
        self.family = family(model)
        self.measured = rates is not None
        self.info = info
        self.seed = info.get("seed")
        self.columns = (["config"] + [k.name for k in self.knobs if k.reachable and k.kind != "precision"] +
                        ["dtype", "op", "evals_per_s", "speedup", "expected_speedup", "max_err", "p99_err",
                         "albedo_err", "pareto"])
        op = _op(model)
        rows = []
        for i, (c, e) in enumerate(zip(self.configs, evaluation.errors)):
            r = {"config": c.describe()}
            for k in self.knobs:
                if k.reachable and k.kind != "precision":
                    r[k.name] = c.labels[k.name] if c.labels[k.name] is not None else "(moot)"
            r.update(dtype=c.labels["precision"], op=op,
                     evals_per_s=None if rates is None else rates[i],
                     speedup=None if speedups is None else speedups[i],
                     expected_speedup=None if expected[i] is None else 1.0 / expected[i], **e)
            rows.append(r)
        thr = [r["speedup"] if r["speedup"] is not None else (r["expected_speedup"] or 1.0) for r in rows]
        for r, p in zip(rows, _pareto_mask([r["p99_err"] for r in rows], thr)):
            r["pareto"] = bool(p)
        self._rows = rows

    # --- access
    def __len__(self):
        return len(self._rows)

    def __iter__(self):
        return iter(self.to_records())

    def __getitem__(self, i):
        if isinstance(i, str):
            if i not in self.columns:
                raise KeyError(f"column {i!r}; columns: {', '.join(self.columns)}")
            return [r[i] for r in self._rows]
        return dict(self._rows[i])

    def to_records(self) -> list:
        """Rows as a list of dicts (column -> value)."""
        return [dict(r) for r in self._rows]

    def to_dict(self) -> dict:
        """Columns as a dict of lists."""
        return {c: [r[c] for r in self._rows] for c in self.columns}

    def to_pandas(self):
        """The table as a ``pandas.DataFrame`` (raises ImportError naming pandas when it is not
        installed: pandas is optional; ``to_records()`` / ``to_dict()`` need nothing)."""
        try:
            import pandas as pd
        except ImportError:
            raise ImportError("Table.to_pandas() needs pandas, which is not installed (pip install pandas); "
                              "Table.to_records() and Table.to_dict() work without it") from None
        return pd.DataFrame(self.to_records(), columns=self.columns)

    def pareto_front(self, metric="p99") -> list:
        """Row indices on the Pareto front of throughput (live speedup, else expected) against
        the given error metric, sorted by error."""
        col = _check_metric(metric)
        thr = [r["speedup"] if r["speedup"] is not None else (r["expected_speedup"] or 1.0) for r in self._rows]
        err = [r[col] for r in self._rows]
        idx = [i for i, p in enumerate(_pareto_mask(err, thr)) if p]
        return sorted(idx, key=lambda i: (err[i], -thr[i]))

    # --- rendering
    def _title(self) -> str:
        from .plot import describe
        m = "live" if self.measured else "not measured"
        return (f"{describe(self.model)} — {len(self)} configurations ({self.family}); errors vs the most accurate "
                f"on {len(self.directions)} direction pairs (seed {self.seed}), floor {self.floor:.2e}; "
                f"throughput {m}")

    def _cells(self):
        return [[_fmt_cell(r[c], c) for c in self.columns] for r in self._rows]

    def __str__(self):
        cells = self._cells()
        w = [max(len(c), *(len(row[j]) for row in cells)) for j, c in enumerate(self.columns)]
        lines = [self._title(), "  ".join(c.ljust(w[j]) for j, c in enumerate(self.columns)),
                 "  ".join("-" * x for x in w)]
        lines += ["  ".join(v.ljust(w[j]) for j, v in enumerate(row)) for row in cells]
        return "\n".join(lines)

    def __repr__(self):
        return f"<bsdfkit.tradeoff.Table: {len(self)} configurations of {type(self.model).__name__}>"

    def _repr_markdown_(self):
        cells = self._cells()
        lines = [f"**{self._title()}**", "", "| " + " | ".join(self.columns) + " |",
                 "|" + "|".join("---" for _ in self.columns) + "|"]
        for r, row in zip(self._rows, cells):
            row = [f"**{v}**" if r["pareto"] and v else v for v in row]
            lines.append("| " + " | ".join(v.replace("|", "\\|") for v in row) + " |")
        return "\n".join(lines)

    def _repr_html_(self):
        esc = _html.escape
        head = "".join(f"<th>{esc(c)}</th>" for c in self.columns)
        body = []
        for r, row in zip(self._rows, self._cells()):
            style = ' style="font-weight:bold"' if r["pareto"] else ""
            body.append(f"<tr{style}>" + "".join(f"<td>{esc(v)}</td>" for v in row) + "</tr>")
        return (f"<div><p>{esc(self._title())} (bold: Pareto front)</p><table><thead><tr>{head}</tr></thead>"
                f"<tbody>{''.join(body)}</tbody></table></div>")


# ============================================================================ public API

def _check_int(x, name, lo):
    if isinstance(x, bool) or not isinstance(x, numbers.Integral):
        raise TypeError(f"{name}: expected an integer, got {type(x).__name__}")
    if int(x) < lo:
        raise ValueError(f"{name}: must be >= {lo}, got {x}")
    return int(x)


def _check_metric(metric) -> str:
    if not isinstance(metric, str) or metric not in METRICS:
        raise ValueError(f"metric: must be one of {', '.join(map(repr, METRICS))}, got {metric!r}")
    return METRICS[metric]


def _check_tol(tol) -> float:
    if isinstance(tol, bool) or not isinstance(tol, (numbers.Real, np.floating, np.integer)):
        raise TypeError(f"tol: expected a real number, got {type(tol).__name__}")
    t = float(tol)
    if math.isnan(t) or t < 0:
        raise ValueError(f"tol: must be a number >= 0 (inf allowed), got {t}")
    return t


def tradeoff(model, directions=None, n: int = 8192, seed: int = 0, *, n_albedo: int = 4096, measure: bool = True,
             n_timing: int = 65536, repeats: int = 3, rounds: int = 1, costs: dict | None = None) -> Table:
    """Throughput and error of every reachable knob configuration of ``model``.

    directions: ``None`` (the default set, :func:`direction_set` with ``n`` rows and ``seed``),
    a :class:`DirectionSet`, or a pair ``(wo, wi)`` of direction arrays (float64 unit vectors;
    delta lobes, which ``eval`` cannot reach, are then sampled at those ``wo``).
    Errors: ``max_err`` / ``p99_err`` (relative error of f |cos theta_i|) and ``albedo_err``
    against the most accurate configuration (definitions in the module docstring). float32
    configurations are run on float32 directions.

    Throughput (``measure=True``): each configuration's ``eval`` (``sample`` for models made only
    of delta lobes) on ``n_timing`` pairs with a preallocated ``out=``, timed back to back with
    the most accurate configuration, best of ``repeats`` (over ``rounds`` rounds), at the current
    ``bsdfkit.set_num_threads``; ``speedup`` is that same-run ratio. ``expected_speedup`` is what
    the shipped cost table predicts (the number :func:`simplify` ranks by; see the module
    docstring for why simplify does not use the live figure). DFG tables are built before timing.
    costs: a cost table in the :func:`knob_costs` format to use instead of the shipped one.
    """
    _check_model(model)
    n, seed, n_albedo = _check_int(n, "n", 16), _check_int(seed, "seed", 0), _check_int(n_albedo, "n_albedo", 16)
    n_timing, repeats, rounds = (_check_int(n_timing, "n_timing", 1), _check_int(repeats, "repeats", 1),
                                 _check_int(rounds, "rounds", 1))
    ev = _Evaluation(model, directions, n, seed, n_albedo)
    rates = speedups = None
    if measure:
        rates, speedups = _measure(ev.configs, _op(model), n_timing, repeats, rounds, seed)
    costs = _check_costs(costs)
    expected = _costs_for(model, ev.configs, costs)
    info = {"seed": seed, "n": n, "n_albedo": n_albedo, "n_timing": n_timing, "repeats": repeats, "rounds": rounds,
            "threads": _threads(), "cost_table": costs.get("machine")}
    return Table(model, ev, rates, speedups, expected, info)


def _threads():
    from . import _core
    return _core.get_num_threads()


@dataclass
class SimplifyReport:
    """What :func:`simplify` chose and why.

    model: the simplified model; dtype: ``np.float32`` or ``np.float64``, the precision to call
    it with (feed directions of that dtype); config: ``{knob: label}`` of every reachable knob
    (precision included); changes: ``[(knob, input setting, chosen setting, reason)]`` for every
    knob whose setting differs from the input model's (and the precision, when float32);
    error: ``{"max": ..., "p99": ..., "albedo": ...}`` of the chosen configuration; expected_speedup:
    against the most accurate configuration, from the cost table (``None`` when the configuration
    is not in it); speedup_vs_input: the same against the input model's own configuration
    (float64 calls), when both are in the table; ranked_by: ``"cost table"`` or ``"registry
    order"``; reference: the most accurate model; kept: ``[(knob, reason)]`` for reachable knobs
    left at the most accurate setting although a cheaper one exists.
    """

    input_model: BxDF
    model: BxDF
    dtype: type
    config: dict
    changes: list
    kept: list
    error: dict
    tol: float
    metric: str
    expected_speedup: float | None
    speedup_vs_input: float | None
    ranked_by: str
    reference: BxDF
    description: str
    n_configurations: int
    n_within_tol: int
    seed: int
    floor: float
    notes: list = field(default_factory=list)

    def summary(self) -> str:
        """One line: chosen configuration, error and expected speedup."""
        ch = self.description
        sp = "unknown" if self.expected_speedup is None else f"{self.expected_speedup:.2f}×"
        return (f"{ch} | {self.metric} error {self.error[self.metric]:.2e} <= tol {self.tol:g} | "
                f"expected speedup {sp} | dtype {np.dtype(self.dtype).name}")

    def __str__(self):
        from .plot import describe
        L = [f"simplify({describe(self.input_model)}, tol={self.tol:g}, metric={self.metric!r}, seed={self.seed})",
             f"  chosen: {self.summary()}",
             f"  errors vs the most accurate configuration: max {self.error['max']:.2e}, p99 {self.error['p99']:.2e}, "
             f"albedo {self.error['albedo']:.2e} (floor {self.floor:.1e})",
             f"  {self.n_within_tol} of {self.n_configurations} configurations within tol; ranked by "
             f"{self.ranked_by}"]
        if self.speedup_vs_input is not None:
            L.append(f"  expected speedup over the input configuration: {self.speedup_vs_input:.2f}×")
        for k, a, b, why in self.changes:
            L.append(f"  - {k}: {a} -> {b}: {why}")
        for k, why in self.kept:
            L.append(f"  - {k} kept: {why}")
        L += [f"  note: {x}" for x in self.notes]
        L.append(f"  model: {self.model!r}, call with {np.dtype(self.dtype).name} directions")
        return "\n".join(L)

    def _repr_markdown_(self):
        return "```\n" + str(self) + "\n```"


def _input_label(model, spec) -> str:
    if spec.name == "precision":
        return "float64"
    v = model._params[spec.param]
    if spec.kind == "lobe":
        return "keep"
    return _label(v)


def simplify(model, tol, metric: str = "p99", directions=None, seed: int = 0, *, n: int = 8192,
             n_albedo: int = 4096, costs: dict | None = None):
    """The cheapest configuration of ``model`` whose error against the most accurate one is
    <= ``tol``: returns ``(simplified_model, SimplifyReport)``.

    metric: ``"p99"`` (default), ``"max"`` (relative error of f |cos theta_i|) or ``"albedo"``
    (absolute directional-albedo error); definitions in the module docstring. Errors are measured
    on ``directions`` (default: :func:`direction_set` of ``n`` rows drawn with ``seed``); float32
    configurations on float32 directions, so ``report.dtype`` is the precision to call the result
    with. Lobes whose removal stays within ``tol`` are dropped (e.g. a FilamentStandard with
    clear_coat 0.001 gets clear_coat 0 and the compiled variant without the coat).

    "Cheapest" is ranked by the shipped cost table (bench/tradeoff.py), not by a timing taken
    now, so the result is deterministic for a given seed: among the configurations within tol
    that cost at most (1 + ``COST_RESOLUTION``) x the cheapest one, the one dropping the most
    lobes, then the most accurate; configurations missing from the table count as costing as
    much as the most accurate one, and a family without a table is ranked by registry order (most
    knobs at cheaper settings).
    ``tol = 0`` returns the most accurate configuration (float64); a huge tol the cheapest one
    (to that resolution). Knobs that change the modelled material rather than approximate it
    (min_roughness, clear-coat layering, ...) keep the input's value; reachable knobs are set to
    the chosen configuration, so an input using an approximation (e.g. Filament's default
    Lambert diffuse) can come back more accurate (Burley) if the approximation exceeds ``tol``.
    costs: a cost table in the :func:`knob_costs` format (e.g. ``bench/tradeoff.py`` run on
    another machine) to rank by instead of the shipped one.
    """
    _check_model(model)
    tol = _check_tol(tol)
    col = _check_metric(metric)
    seed, n, n_albedo = _check_int(seed, "seed", 0), _check_int(n, "n", 16), _check_int(n_albedo, "n_albedo", 16)
    table = _check_costs(costs)
    ev = _Evaluation(model, directions, n, seed, n_albedo)
    costs = _costs_for(model, ev.configs, table)
    cands = [i for i, e in enumerate(ev.errors) if e[col] <= tol] if tol > 0 else [0]
    best, ranked_by = _pick(cands, costs, ev.configs, [e[col] for e in ev.errors])
    cfg, err = ev.configs[best], ev.errors[best]
    # explanations: each knob's error alone (the configuration with only that knob changed)
    single = {}
    for i, c in enumerate(ev.configs):
        ch = c.changes()
        if len(ch) == 1:
            (k, lab), = ch.items()
            single[(k, lab)] = ev.errors[i][col]
    specs = {s.name: s for s in _specs(model)}
    changes, kept, notes = [], [], []
    for name, s in specs.items():
        lab = cfg.labels[name]
        if lab is None:
            continue
        before = _input_label(model, s)
        if lab != before:
            alone = single.get((name, lab))
            why = ("most accurate setting" if cfg.index[name] == 0 else
                   f"{metric} error of this change alone {alone:.2e} <= tol" if alone is not None else
                   "part of the cheapest configuration within tol")
            if cfg.index[name] == 0 and before in s.labels and s.labels.index(before) > 0:
                e_in = single.get((name, before))
                why = (f"the input's {before!r} alone has {metric} error {e_in:.2e} > tol" if e_in is not None
                       and e_in > tol else "the input's setting is not part of the cheapest configuration within tol")
            if s.kind == "lobe" and lab == "drop":
                why += "; the model gets the compiled variant without this lobe"
            changes.append((name, before, lab, why))
        elif cfg.index[name] == 0 and len(s.settings) > 1 and any(c.index[name] > 0 for c in ev.configs):
            errs = [(lab2, single[(name, lab2)]) for lab2 in s.labels[1:] if (name, lab2) in single]
            if errs:
                lab2, e2 = min(errs, key=lambda t: t[1])
                kept.append((name, f"cheapest alternative {lab2!r} alone has {metric} error {e2:.2e}" +
                             (" > tol" if e2 > tol else " (within tol, but not in the cheapest configuration)")))
    if tol == 0:
        notes.append("tol = 0: the most accurate configuration")
    ref_cost = costs[0]
    exp = None if costs[best] is None or ref_cost is None else ref_cost / costs[best]
    in_cfg = _input_config(model, ev.configs)
    vs_in = None
    if in_cfg is not None and costs[in_cfg] is not None and costs[best] is not None:
        vs_in = costs[in_cfg] / costs[best]
    report = SimplifyReport(
        input_model=model, model=cfg.model, dtype=cfg.dtype, config=dict(cfg.labels), changes=changes, kept=kept,
        error={k: err[v] for k, v in METRICS.items()}, tol=tol, metric=metric, expected_speedup=exp,
        speedup_vs_input=vs_in, ranked_by=ranked_by, reference=ev.reference.model, description=cfg.describe(),
        n_configurations=len(ev.configs),
        n_within_tol=len(cands) if tol > 0 else sum(e[col] <= 0 for e in ev.errors), seed=seed, floor=ev.floor,
        notes=notes)
    return cfg.model, report


def _input_config(model, configs):
    """Index of the configuration equal to the input model called in float64, if reachable."""
    for i, c in enumerate(configs):
        if c.dtype is np.float64 and c.model == model:
            return i
    return None


# ============================================================================ plot

def pareto(table: Table, ax=None, metric: str = "p99"):
    """Throughput against error of every configuration in ``table`` (a :class:`Table`), the
    Pareto front highlighted and labelled. x: the error ``metric`` (log scale; error-0 rows, the
    most accurate configuration among them, are drawn at the left edge), y: live speedup over
    the most accurate configuration (expected speedup when the table was not measured).
    Returns the Axes, with the numbers in ``ax.bsdfkit_data`` (error, speedup, front, labels)."""
    if not isinstance(table, Table):
        raise TypeError(f"table: expected a bsdfkit.tradeoff.Table, got {type(table).__name__}")
    col = _check_metric(metric)
    if ax is None:
        import matplotlib.pyplot as plt  # lazy
        ax = plt.figure(figsize=(11.5, 5.0), layout="constrained").add_subplot()
    rows = table.to_records()
    err = np.array([r[col] for r in rows], float)
    live = table.measured
    thr = np.array([(r["speedup"] if live else (r["expected_speedup"] or 1.0)) for r in rows], float)
    front = table.pareto_front(metric)
    pos = err[err > 0]
    lo = (pos.min() / 10) if pos.size else 1e-8
    x = np.where(err > 0, err, lo)
    is32 = np.array([r["dtype"] == "float32" for r in rows])
    ax.scatter(x[~is32], thr[~is32], s=18, c="0.65", label="float64", zorder=2)
    ax.scatter(x[is32], thr[is32], s=18, c="0.65", marker="^", label="float32", zorder=2)
    fx, fy = x[front], thr[front]
    ax.plot(fx, fy, "-o", c="tab:red", ms=6, lw=1.5, label="Pareto front", zorder=3, drawstyle="steps-post")
    # Numbers at the points, the configurations listed beside the plot: front points often sit
    # close together (same error, similar speed) and long labels would overlap.
    lines = []
    for k, i in enumerate(front, 1):
        ax.annotate(str(k), (x[i], thr[i]), textcoords="offset points", xytext=(4, 3 + 7 * ((k - 1) % 2)),
                    fontsize=8, color="tab:red", weight="bold")
        e = "0" if err[i] == 0 else f"{err[i]:.1e}"
        lines.append(f"{k}. {rows[i]['config']}  ({thr[i]:.2f}x, {metric} {e})")
    ax.text(1.02, 1.0, "Pareto front\n" + "\n".join(lines), transform=ax.transAxes, va="top", ha="left",
            fontsize=7.5, family="monospace", color="tab:red")
    ax.set_xscale("log")
    ax.set_xlabel(f"{metric} relative error of f·|cos θi| vs the most accurate configuration"
                  + (" (0 drawn at the left)" if (err == 0).any() else ""))
    ax.set_ylabel("speedup over the most accurate (" + ("measured" if live else "cost table") + ")")
    from .plot import describe
    ax.set_title(describe(table.model), fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    ax.bsdfkit_data = {"error": err, "speedup": thr, "front": list(front), "labels": [r["config"] for r in rows],
                       "metric": metric}
    return ax
