"""Errors: the direction sets and the relative error of a configuration against a reference."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._enums import BxDFFlags
from ..models import BxDF
from .configs import Config, _check_model, _reference_config, configurations
from .._validate import check_int as _check_int

__all__ = ["FLOOR_FRACTION", "ALBEDO_COS_THETA", "MIN_COS", "DirectionSet", "direction_set", "relative_error",
           "CONVERGED", "is_stochastic", "relative_rms", "color_weights", "COLOR_STEP_NM"]


#: floor = FLOOR_FRACTION * mean(albedo_ref) / pi (see the module docstring).
FLOOR_FRACTION = 1e-3


#: cos theta_o of the directional-albedo set (mirrored below the surface for transmissive models).
ALBEDO_COS_THETA = (1.0, 0.7, 0.4, 0.15, 0.05, 0.01)


#: Smallest |cos theta| of the default direction set.
MIN_COS = 1e-3


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
    """The directions every configuration is compared on (float64 arrays; made by
    :func:`direction_set`, or by hand to compare on one's own directions).

    Parameters
    ----------
    wo, wi : numpy.ndarray, shape (N, 3)
        Pairs evaluated with ``eval`` (stratified pairs and the non-delta samples of the
        reference).
    delta_wo, delta_uc, delta_u : numpy.ndarray
        Inputs of the delta-lobe rows, where each configuration is sampled with the same uniforms.
    albedo_wo : numpy.ndarray, shape (K, 3)
        The directions of the directional-albedo set.
    albedo_uc, albedo_u : numpy.ndarray, shapes (M,) and (M, 2)
        Its uniforms (M samples of the reference per wo).
    seed : int or None, optional
        The seed it was drawn with (None if given by the user).
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
    made only of delta lobes), plus the albedo set with ``n_albedo`` samples per wo.

    Parameters
    ----------
    model : BxDF
        The model.
    n : int, optional
        Rows.
    seed : int, optional
        Seed of the draws.
    n_albedo : int, optional
        Albedo samples per wo.

    Returns
    -------
    DirectionSet
        The directions.

    Examples
    --------
    >>> import bsdfkit as bk
    >>> ds = bk.tuning.direction_set(bk.Diffuse(0.5), n=64, n_albedo=16)
    >>> ds.wo.shape, ds.wi.shape
    ((64, 3), (64, 3))
    """
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


def relative_error(v_ref, v, floor: float) -> np.ndarray:
    """``|v - v_ref| / max(|v_ref|, floor)`` elementwise (float64).

    Parameters
    ----------
    v_ref : array_like
        The reference values.
    v : array_like
        The values compared, broadcast with ``v_ref``.
    floor : float
        The smallest denominator.

    Returns
    -------
    numpy.ndarray
        The relative errors.

    Examples
    --------
    >>> from bsdfkit.tuning import relative_error
    >>> relative_error([1.0, 0.0], [1.1, 0.01], floor=0.1).round(6)
    array([0.1, 0.1])
    """
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
        self.k, self.m = k, m
        # A reference whose samples carry a pdf only proportional to the true density (pbrt-v4's
        # layered walks: as low as 1e-13 where pdf() gives 0.57) cannot weight other
        # configurations' f by 1 / pdf. Then every configuration's albedo is the mean of its own
        # sampling weights f |cos| / pdf (exact in expectation, pbrt's rho) over the same uniforms.
        self.proportional = bool(np.any(s.pdf_is_proportional & s.valid))
        self.w_wo, self.w_uc, self.w_u = wo, uc, u
        self.w_group = np.repeat(np.arange(k), m)
        if self.proportional:
            s = _no_rows(s)
        delta = s.valid & ((s.flags & int(BxDFFlags.Specular)) != 0)
        smooth = s.valid & ~delta & (s.pdf > 0)
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


def _no_rows(s):
    """A sample result with every row invalid (no eval rows for the albedo)."""
    from dataclasses import replace
    return replace(s, valid=np.zeros_like(s.valid))


def _weight_albedo(cfg, prep):
    """Albedo (K, 3) of a configuration as the mean of its own sampling weights f |cos| / pdf over
    the albedo uniforms (spectral mode: per-wavelength weights integrated as :func:`color_weights`)."""
    m, dt = cfg.model, cfg.dtype
    wo, uc, u = prep.w_wo.astype(dt), prep.w_uc.astype(dt), prep.w_u.astype(dt)
    if cfg.spectral:
        lam, W = color_weights()
        v = np.zeros((len(wo), 3))
        for g in range(len(lam)):
            for order, hero in _heroes(m):
                w = m.sample(wo, uc, u, wavelengths=lam[g][order]).weight.astype(np.float64)
                v += w @ W[g] if hero is None else w[:, :1] * W[g][hero]
    else:
        v = m.sample(wo, uc, u).weight.astype(np.float64)
    v = np.where(np.isfinite(v), v, 0.0)
    alb = np.zeros((prep.k, 3))
    np.add.at(alb, prep.w_group, v)
    return alb / prep.m


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


#: Spacing (nm) of the ``color`` knob's wavelength quadrature over [360, 830] nm.
COLOR_STEP_NM = 5.0


def color_weights():
    """The ``color`` knob's view of a spectral result, as a renderer sees it: the model lit by a
    D65 white furnace and integrated to linear sRGB. Returns (wavelengths (G, 4), W (G, 4, 3)),
    rgb = sum over groups g of f(wavelengths[g]) @ W[g]: the values at nodes every 5 nm over
    [360, 830] nm (95 nodes, one zero-weight pad to fill groups of 4), joined piecewise linearly and
    projected exactly as RGB mode projects a reflectance spectrum (``Spectrum.to_rgb("reflectance",
    "D65")``, bsdfkit.spectral.colorimetry's Mitsuba projection: CIE 1931 x-bar y-bar z-bar times
    D65, XYZ to linear sRGB), so that a spectrum linear between the nodes integrates to its RGB-mode
    colour; each node's weight is the projection's grid weights times the node's hat function."""
    from ..spectral import colorimetry as cm
    w = np.arange(360.0, 830.0 + 0.5 * COLOR_STEP_NM, COLOR_STEP_NM)
    gw, GW = cm.grid_weights(illuminant="D65", normalization="mitsuba")
    hat = np.maximum(0.0, 1.0 - np.abs(gw[None, :] - w[:, None]) / COLOR_STEP_NM)   # (nodes, grid)
    W = cm.xyz_to_srgb(hat @ GW)
    pad = (-len(w)) % 4
    w = np.concatenate([w, np.full(pad, w[-1])])
    W = np.concatenate([W, np.zeros((pad, 3))])
    return w.reshape(-1, 4), W.reshape(-1, 4, 3)


def _heroes(m):
    """(wavelength order, weight rows) of one group: a dispersive model keeps only its first (hero)
    wavelength across a refraction, so each wavelength is evaluated as the hero (4 calls, channel
    0 of each); any other model evaluates the group in one call."""
    from ..models._spectral import _spectral_core
    if getattr(_spectral_core(m), "dispersive", False):
        return [(np.roll(np.arange(4), -r), r) for r in range(4)]
    return [(np.arange(4), None)]


def _eval_cos_spectral(m, dtype, wo, wi):
    if len(wo) == 0:
        return np.empty((0, 3))
    lam, W = color_weights()
    out = np.zeros((len(wo), 3))
    wo_, wi_ = wo.astype(dtype), wi.astype(dtype)
    for g in range(len(lam)):
        for order, hero in _heroes(m):
            f = m.eval(wo_, wi_, wavelengths=lam[g][order]).astype(np.float64)
            out += f @ W[g] if hero is None else f[:, :1] * W[g][hero]
    return out * np.abs(wi[:, 2:3])


def _delta_cos_spectral(m, dtype, wo, uc, u, wi_ref, flags_ref):
    if len(wo) == 0:
        return np.empty((0, 3))
    lam, W = color_weights()
    out = np.zeros((len(wo), 3))
    for g in range(len(lam)):
        for order, hero in _heroes(m):
            s = m.sample(wo.astype(dtype), uc.astype(dtype), u.astype(dtype), wavelengths=lam[g][order])
            wi = s.wi.astype(np.float64)
            same = s.valid & (s.flags == flags_ref) & (np.max(np.abs(wi - wi_ref), axis=1) < 1e-3)
            f = s.f.astype(np.float64)
            v = f @ W[g] if hero is None else f[:, :1] * W[g][hero]
            out += np.where(same[:, None], v * np.abs(wi[:, 2:3]), 0.0)
    return out


def _values(cfg: Config, prep: _Prepared):
    """(values on the error set (N, 3), albedo (K, 3)) of one configuration (spectral mode: the
    per-wavelength values integrated to linear sRGB, :func:`color_weights`)."""
    ds, m, dt = prep.ds, cfg.model, cfg.dtype
    ev, dl = (_eval_cos_spectral, _delta_cos_spectral) if cfg.spectral else (_eval_cos, _delta_cos)
    v = np.concatenate([ev(m, dt, ds.wo, ds.wi),
                        dl(m, dt, ds.delta_wo, ds.delta_uc, ds.delta_u, prep.d_wi, prep.d_flags)])
    if prep.proportional:
        return v, _weight_albedo(cfg, prep)
    alb = np.zeros((prep.k, 3))
    if len(prep.a_wo):
        np.add.at(alb, prep.a_group, ev(m, dt, prep.a_wo, prep.a_wi) * prep.a_w[:, None])
    if len(prep.ad_wo):
        vd = dl(m, dt, prep.ad_wo, prep.ad_uc, prep.ad_u, prep.ad_wi, prep.ad_flags)
        np.add.at(alb, prep.ad_group, vd * prep.ad_w[:, None])
    return v, alb


#: The converged reference of a stochastic model: its parameters with these settings (issue 12).
CONVERGED = {"n_samples": 256, "max_depth": 100}
#: Pairs of the default direction set of a stochastic model (each eval is a random walk).
STOCHASTIC_N = 512
#: Seed offset of the converged reference's realization (distinct from every configuration's).
_REF_SEED = 1_000_003


def is_stochastic(model) -> bool:
    """True when ``model.eval`` is a stochastic estimate (the instance's ``exact_eval`` is False)."""
    return not getattr(model, "exact_eval", True)


def relative_rms(v_ref, v) -> float:
    """``sqrt(mean((v - v_ref)^2) / mean(v_ref^2))`` over every pair and channel (float64)."""
    v_ref, v = np.asarray(v_ref, np.float64), np.asarray(v, np.float64)
    if v_ref.size == 0:
        return 0.0
    den = float(np.mean(v_ref * v_ref))
    return float(np.sqrt(np.mean((v - v_ref) ** 2) / den)) if den > 0 else 0.0


def _children_mapped(model, fn):
    """A composite (bk.Mix, ...) with ``fn`` applied to its child models; None for other models."""
    kids = {k: v for k, v in model._params.items() if isinstance(v, BxDF)}
    if not kids:
        return None
    p = dict(model._params)
    p.update({k: fn(v) for k, v in kids.items()})
    return type(model)._from_params(p)


def _converged(model):
    """The converged reference of a stochastic model (CONVERGED settings, its own realization); a
    composite's: its stochastic children's."""
    if not is_stochastic(model):
        return model
    comp = _children_mapped(model, _converged)
    if comp is not None:
        return comp
    p = dict(model._params)
    p.update(CONVERGED, method="stochastic") if "method" in p else p.update(CONVERGED)
    p["seed"] = (p["seed"] + _REF_SEED) % (2 ** 31)
    return type(model)._from_params(p)


def _reseeded(model, k):
    if not is_stochastic(model):
        return model
    comp = _children_mapped(model, lambda c: _reseeded(c, k))
    if comp is not None:
        return comp
    p = dict(model._params)
    p["seed"] = (p["seed"] + k) % (2 ** 31)
    return type(model)._from_params(p)


class _Evaluation:
    """Errors of every configuration of a model against a reference: its most accurate
    configuration (``reference="accurate"``, :func:`tradeoff`) or the input model itself, called
    in float64 (``reference="input"``, :func:`simplify`). ``allow`` as in :func:`configurations`."""

    def __init__(self, model, directions, n, seed, n_albedo, *, allow="all", reference="accurate", progress=False,
                 what="tradeoff"):
        self.model = model
        self.configs = configurations(model, allow)
        if isinstance(reference, BxDF):   # a user's reference (e.g. a bk.Custom), called in float64
            _check_comparable(model, reference)
            self.reference = Config({}, {}, reference, np.float64, "reference")
        elif reference == "input":
            self.reference = next(c for c in self.configs if c.dtype is np.float64 and c.model == model)
        else:
            self.reference = self.configs[0]
            assert self.reference.is_reference
        # Stochastic models (or a deterministic input whose configurations include stochastic
        # ones): compared against the converged reference, noise and bias separated.
        self.stochastic = any(is_stochastic(c.model) for c in self.configs)
        if directions is None and self.stochastic and not _all_delta(model):
            # stratified pairs only: importance-sampled pairs would sit on a narrow coat highlight
            # (deterministic and 1e3 x brighter), which would then dominate the relative RMS
            ds = direction_set(model, 2 * n, seed, n_albedo=n_albedo)
            self.directions = DirectionSet(ds.wo[:n], ds.wi[:n], np.empty((0, 3)), np.empty(0), np.empty((0, 2)),
                                           ds.albedo_wo, ds.albedo_uc, ds.albedo_u, seed)
        elif directions is None:
            self.directions = direction_set(model, n, seed, n_albedo=n_albedo)
        else:
            self.directions = _user_directions(model, directions, seed, n_albedo)
        ref_model = self.reference.model
        self.converged = _converged(ref_model) if is_stochastic(ref_model) else None
        ref_cfg = self.reference if self.converged is None else Config(
            self.reference.labels, self.reference.index, self.converged, np.float64, self.reference.key)
        prep = _Prepared(ref_model, self.directions)
        v_ref, a_ref = _values(ref_cfg, prep)
        self.reference_albedo = a_ref
        mean_alb = float(np.mean(np.abs(a_ref)))
        self.floor = FLOOR_FRACTION * mean_alb / math.pi if mean_alb > 0 else 1e-30
        # the converged reference's own noise (two realizations), part of every rms_err
        self.reference_noise = None
        if self.converged is not None:
            v_ref2 = _eval_cos(_reseeded(self.converged, 1), np.float64, self.directions.wo, self.directions.wi)
            d = v_ref[:len(self.directions.wo)] - v_ref2
            self.reference_noise = relative_rms(v_ref, v_ref + np.concatenate([d, 0 * v_ref[len(d):]]) / np.sqrt(2.0))
        ref_noise = self.reference_noise or 0.0
        self.errors = []
        from .._progress import Progress
        prog = Progress(progress, len(self.configs), "errors of configuration", what)
        try:
            for i, c in enumerate(self.configs):
                self.errors.append(self._row(c, prep, v_ref, a_ref, ref_noise))
                prog(i + 1)
        finally:
            prog.close()

    def _row(self, c, prep, v_ref, a_ref, ref_noise):
        """Error columns of configuration ``c`` against the reference values."""
        v, a = (v_ref, a_ref) if (c is self.reference and self.converged is None) else _values(c, prep)
        e = relative_error(v_ref, v, self.floor)
        row = {"max_err": float(np.max(e)) if e.size else 0.0,
               "p99_err": float(np.quantile(e, 0.99)) if e.size else 0.0,
               "albedo_err": float(np.max(np.abs(a - a_ref))) if a.size else 0.0,
               "rms_err": relative_rms(v_ref, v), "noise": None, "bias": None}
        if self.stochastic:
            # noise: the RMS difference of two realizations (seeds) / sqrt 2; bias: the rest
            if is_stochastic(c.model):
                c2 = Config(c.labels, c.index, _reseeded(c.model, 1), c.dtype, c.key)
                v2 = np.concatenate([_eval_cos(c2.model, c.dtype, self.directions.wo, self.directions.wi),
                                     v[len(self.directions.wo):]])
                noise = relative_rms(v_ref, v_ref + (v - v2) / np.sqrt(2.0))
            else:
                noise = 0.0
            row["noise"] = noise
            row["bias"] = float(np.sqrt(max(0.0, row["rms_err"] ** 2 - noise ** 2 - ref_noise ** 2)))
        return row


def _check_comparable(model, reference) -> None:
    """A reference other than the model's own configurations must have the same kind of specular
    (delta) lobes: delta rows are compared by sampling both with the same uniforms."""
    _check_model(reference, "reference")
    spec = int(BxDFFlags.Specular)
    if bool(model.flags & spec) != bool(reference.flags & spec):
        has, lacks = (model, reference) if model.flags & spec else (reference, model)
        raise ValueError(f"reference: {type(has).__name__} has specular (delta) lobes and {type(lacks).__name__} "
                         "has none; their values cannot be compared pair by pair (give a reference with the "
                         "same kind of lobes, e.g. a rough model against a rough or user-defined one)")
