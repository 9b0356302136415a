"""Independent float64 numpy oracle of pbrt-v4's ``HairBxDF`` (Chiang et al. 2016) and
``NormalizedFresnelBxDF``, written from the papers and pbrt-v4's formulas (pbrt-v4 book
sec. 9.9; d'Eon et al. 2011 for Mp), not from bsdfkit's C++. Follows pbrt-v4's branches
literally (v <= 0.1 log-space Mp, two atan2 for phi, wrap of Delta phi), and computes
FresnelMoment1 by quadrature instead of pbrt-v4's polynomial.

Also the frame mapping to Mitsuba 3's ``hair`` plugin (:func:`to_mitsuba_frame`) and the per-lobe
terms used by ``bsdfkit.plot`` hair views (:func:`lobe_terms`).
"""
from __future__ import annotations

import numpy as np

P_MAX = 3
LOBES = ("R", "TT", "TRT", "rest")


def fr_dielectric(cos_i, eta):
    """Unpolarised dielectric Fresnel reflectance, signed cos (inside flips eta), TIR -> 1."""
    cos_i = np.clip(cos_i, -1.0, 1.0)
    eta = np.where(cos_i < 0, 1.0 / eta, eta)
    c = np.abs(cos_i)
    sin2_t = (1 - c * c) / eta**2
    cos_t = np.sqrt(np.maximum(0.0, 1 - sin2_t))
    with np.errstate(invalid="ignore", divide="ignore"):
        r_parl = (eta * c - cos_t) / (eta * c + cos_t)
        r_perp = (c - eta * cos_t) / (c + eta * cos_t)
        f = 0.5 * (r_parl**2 + r_perp**2)
    return np.where(sin2_t >= 1, 1.0, f)


def fresnel_moment1_quad(eta, n=4000):
    """int_0^1 Fr(mu, eta) mu dmu by composite Simpson quadrature on n intervals (float64, ~1e-14;
    no eigen-solver, so it is fast on a busy machine). For eta < 1, Fr = 1 below the critical
    cosine mu_c (exactly mu_c^2 / 2) and has a square-root edge there; mu = mu_c + (1 - mu_c) s^2
    makes the rest smooth in s."""
    s = np.linspace(0.0, 1.0, n + 1)
    w = np.ones(n + 1)
    w[1:-1:2], w[2:-1:2] = 4.0, 2.0
    w /= 3.0 * n
    mu_c = float(np.sqrt(1 - eta * eta)) if eta < 1 else 0.0
    mu = mu_c + (1 - mu_c) * s * s
    jac = 2 * (1 - mu_c) * s
    return 0.5 * mu_c * mu_c + float(np.sum(w * fr_dielectric(mu, eta) * mu * jac))


def normalized_fresnel_f(eta, wo, wi, mode="radiance"):
    """pbrt-v4 NormalizedFresnelBxDF::f with c = 1 - 2 int Fr(mu, eta) mu dmu (quadrature)."""
    c = 1 - 2 * fresnel_moment1_quad(eta)
    same = wo[..., 2] * wi[..., 2] > 0
    f = (1 - fr_dielectric(wi[..., 2], eta)) / (c * np.pi)
    if mode == "radiance":
        f = f * eta**2
    return np.where(same, f, 0.0)


# ------------------------------------------------------------------------------- hair

def _params(model):
    p = model._params if hasattr(model, "_params") else model
    return dict(sigma_a=np.asarray(p["sigma_a"], float), eta=float(p["eta"]), beta_m=float(p["beta_m"]),
                beta_n=float(p["beta_n"]), alpha=float(p["alpha"]), h=float(p["h"]))


def _consts(p):
    bm, bn = p["beta_m"], p["beta_n"]
    v0 = (0.726 * bm + 0.812 * bm**2 + 3.7 * bm**20) ** 2
    v = np.array([v0, 0.25 * v0, 4 * v0, 4 * v0])
    s = np.sqrt(np.pi / 8) * (0.265 * bn + 1.194 * bn**2 + 5.372 * bn**22)
    a = np.radians(p["alpha"])
    sin2k = np.array([np.sin(a), np.sin(2 * a), np.sin(4 * a)])
    cos2k = np.array([np.cos(a), np.cos(2 * a), np.cos(4 * a)])
    return v, s, sin2k, cos2k


def I0(x, terms=10):
    """Series of the modified Bessel function I0: sum_{i<terms} x^{2i} / (4^i (i!)^2); pbrt-v4 sums
    10 terms, Mitsuba 3 (``warp.h::detail::i0``) 11. (``terms=None`` elsewhere: scipy's exact I0.)"""
    val, term = np.zeros_like(x), np.ones_like(x)
    for i in range(terms):
        val = val + term
        term = term * x * x / (4.0 * (i + 1) ** 2)
    return val


def log_I0(x, terms=10):
    if terms is None:  # exact (scipy's Bessel function), for showing what the series costs
        from scipy.special import i0e
        return np.log(i0e(x)) + x
    with np.errstate(over="ignore", divide="ignore"):
        big = x + 0.5 * (-np.log(2 * np.pi) + np.log(1 / np.maximum(x, 1e-300)) + 1 / (8 * np.maximum(x, 1e-300)))
        small = np.log(I0(np.minimum(x, 12.0), terms))
    return np.where(x > 12, big, small)


def Mp(cos_i, cos_o, sin_i, sin_o, v, terms=10):
    """d'Eon et al. 2011 eq. 7 as pbrt-v4 evaluates it (log space for v <= 0.1)."""
    a = cos_i * cos_o / v
    b = sin_i * sin_o / v
    if terms is None:  # exact I0: exp(log I0(a) - b) / (2 v sinh(1/v)) in log space
        return np.exp(log_I0(a, None) - b - 1 / v - np.log(v) - np.log1p(-np.exp(-2 / v)))
    if v <= 0.1:
        return np.exp(log_I0(a, terms) - b - 1 / v + 0.6931 + np.log(1 / (2 * v)))
    return np.exp(-b) * I0(a, terms) / (np.sinh(1 / v) * 2 * v)


def logistic(x, s):
    x = np.abs(x)
    return np.exp(-x / s) / (s * (1 + np.exp(-x / s)) ** 2)


def logistic_cdf(x, s):
    return 1 / (1 + np.exp(-x / s))


def trimmed_logistic(x, s, a=-np.pi, b=np.pi):
    return logistic(x, s) / (logistic_cdf(b, s) - logistic_cdf(a, s))


def Phi(p, gamma_o, gamma_t):
    return 2 * p * gamma_t - 2 * gamma_o + p * np.pi


def Np(phi, p, s, gamma_o, gamma_t):
    dphi = phi - Phi(p, gamma_o, gamma_t)
    dphi = np.mod(dphi + np.pi, 2 * np.pi) - np.pi  # pbrt-v4's while loops into [-pi, pi]
    return trimmed_logistic(dphi, s)


def _geometry(p, sin_o):
    cos_o = np.sqrt(np.maximum(0.0, 1 - sin_o**2))
    eta, h = p["eta"], p["h"]
    sin_t = sin_o / eta
    cos_t = np.sqrt(np.maximum(0.0, 1 - sin_t**2))
    with np.errstate(divide="ignore", invalid="ignore"):
        etap = np.sqrt(np.maximum(0.0, eta**2 - sin_o**2)) / cos_o
        sin_gt = np.where(np.isfinite(etap) & (etap > 0), h / etap, 0.0)
    cos_gt = np.sqrt(np.maximum(0.0, 1 - sin_gt**2))
    gamma_t = np.arcsin(np.clip(sin_gt, -1, 1))
    with np.errstate(divide="ignore", invalid="ignore"):
        length = np.where(cos_t > 0, 2 * cos_gt / np.where(cos_t > 0, cos_t, 1.0), np.inf)
        T = np.exp(-p["sigma_a"][None, :] * length[..., None])
    T = np.where(np.isnan(T), 1.0, T)
    return cos_o, gamma_t, T


def Ap(cos_o, eta, h, T):
    """Attenuations A0..A3, shape (..., 4, 3) (Marschner 2003; pbrt-v4 Ap)."""
    cos_gamma_o = np.sqrt(max(0.0, 1 - h * h))
    f = fr_dielectric(cos_o * cos_gamma_o, eta)[..., None]
    a0 = np.broadcast_to(f, T.shape)
    a1 = (1 - f) ** 2 * T
    a2 = a1 * T * f
    with np.errstate(divide="ignore", invalid="ignore"):
        a3 = np.where(1 - T * f > 0, a2 * f * T / (1 - T * f), 0.0)
    return np.stack([a0, a1, a2, a3], axis=-2)


def _tilted(p_idx, sin_o, cos_o, sin2k, cos2k):
    if p_idx == 0:
        sp, cp = sin_o * cos2k[1] - cos_o * sin2k[1], cos_o * cos2k[1] + sin_o * sin2k[1]
    elif p_idx == 1:
        sp, cp = sin_o * cos2k[0] + cos_o * sin2k[0], cos_o * cos2k[0] - sin_o * sin2k[0]
    elif p_idx == 2:
        sp, cp = sin_o * cos2k[2] + cos_o * sin2k[2], cos_o * cos2k[2] - sin_o * sin2k[2]
    else:
        sp, cp = sin_o, cos_o
    return sp, np.abs(cp)


#: Rec. 709 luminance weights (Mitsuba 3 ``luminance()`` in RGB variants).
LUMINANCE = np.array([0.212671, 0.715160, 0.072169])


def hair_terms(model, wo, wi, *, i0_terms=10, weights="average"):
    """(Mp (..., 4), Np (..., 4) (1/(2 pi) for the rest lobe), Ap (..., 4, 3), apPDF (..., 4)).

    pbrt-v4: ``i0_terms=10``, ``weights="average"`` (lobe probabilities from the spectral average
    of Ap). Mitsuba 3 ``hair``: ``i0_terms=11``, ``weights="luminance"``."""
    p = _params(model)
    v, s, sin2k, cos2k = _consts(p)
    wo, wi = np.broadcast_arrays(np.asarray(wo, float), np.asarray(wi, float))
    sin_o, sin_i = wo[..., 0], wi[..., 0]
    cos_i = np.sqrt(np.maximum(0.0, 1 - sin_i**2))
    phi = np.arctan2(wi[..., 2], wi[..., 1]) - np.arctan2(wo[..., 2], wo[..., 1])
    gamma_o = np.arcsin(np.clip(p["h"], -1, 1))
    cos_o, gamma_t, T = _geometry(p, sin_o)
    ap = Ap(cos_o, p["eta"], p["h"], T)
    avg = ap.mean(axis=-1) if weights == "average" else ap @ LUMINANCE
    with np.errstate(divide="ignore", invalid="ignore"):
        appdf = np.where(avg.sum(-1, keepdims=True) > 0, avg / avg.sum(-1, keepdims=True), 0.0)
    mp, npv = [], []
    for k in range(P_MAX):
        sp, cp = _tilted(k, sin_o, cos_o, sin2k, cos2k)
        mp.append(Mp(cos_i, cp, sin_i, sp, v[k], i0_terms))
        npv.append(Np(phi, k, s, gamma_o, gamma_t))
    mp.append(Mp(cos_i, cos_o, sin_i, sin_o, v[P_MAX], i0_terms))
    npv.append(np.full_like(sin_o, 1 / (2 * np.pi)))
    return np.stack(mp, -1), np.stack(npv, -1), ap, appdf


def hair_f(model, wo, wi, *, i0_terms=10):
    """pbrt-v4 HairBxDF::f (divided by |wi.z| where it is not 0), (..., 3)."""
    mp, npv, ap, _ = hair_terms(model, wo, wi, i0_terms=i0_terms)
    fsum = np.sum((mp * npv)[..., None] * ap, axis=-2)
    c = np.abs(np.broadcast_arrays(np.asarray(wo, float), np.asarray(wi, float))[1][..., 2])
    return np.where((c > 0)[..., None], fsum / np.where(c > 0, c, 1.0)[..., None], fsum)


def hair_pdf(model, wo, wi, *, i0_terms=10, weights="average"):
    """pbrt-v4 HairBxDF::PDF: sum_p Mp apPDF_p Np, (...)."""
    mp, npv, _, appdf = hair_terms(model, wo, wi, i0_terms=i0_terms, weights=weights)
    return np.sum(mp * npv * appdf, axis=-1)


def lobe_terms(model, theta_o, theta_i, phi):
    """Longitudinal Mp(theta_i) and azimuthal Np(phi) of each lobe for plots, with wo at
    longitudinal angle theta_o (radians) and azimuth 0 of pbrt's frame; the attenuation Ap (4, 3)
    at that wo. Returns dict(Mp (4, len(theta_i)), Np (4, len(phi)), Ap (4, 3))."""
    p = _params(model)
    v, s, sin2k, cos2k = _consts(p)
    sin_o = np.array(np.sin(theta_o))
    cos_o, gamma_t, T = _geometry(p, sin_o)
    ap = Ap(cos_o, p["eta"], p["h"], T.reshape(3)).reshape(P_MAX + 1, 3)
    gamma_o = np.arcsin(p["h"])
    ti = np.asarray(theta_i, float)
    mp = []
    for k in range(P_MAX + 1):
        sp, cp = _tilted(k, sin_o, cos_o, sin2k, cos2k)
        mp.append(Mp(np.cos(ti), cp, np.sin(ti), sp, v[k]))
    ph = np.asarray(phi, float)
    npv = [Np(ph, k, s, gamma_o, gamma_t) for k in range(P_MAX)] + [np.full_like(ph, 1 / (2 * np.pi))]
    return dict(Mp=np.array(mp), Np=np.array(npv), Ap=ap)


# ------------------------------------------------------------------------------- Mitsuba frame

def to_mitsuba_frame(w):
    """pbrt hair frame -> Mitsuba ``hair`` frame: Mitsuba's fibre axis is local y and its azimuth
    atan2(z, x), pbrt's are x and atan2(z, y); so mi = (pbrt.y, pbrt.x, pbrt.z). Both keep z as
    the shading normal, so |cos| factors are the same."""
    w = np.asarray(w, float)
    return np.stack([w[..., 1], w[..., 0], w[..., 2]], axis=-1)


def wo_for_h(h, theta_o):
    """A pbrt-frame wo (z > 0) at longitudinal angle theta_o whose Mitsuba-derived offset equals h.

    Mitsuba derives h from its si.wi (= pbrt wo): gamma = +-acos(z / sqrt(x^2 + z^2)) (+ when
    x < 0), h = sin gamma, i.e. in pbrt's frame h = -wo.y / sqrt(wo.y^2 + wo.z^2) for wo.z >= 0.
    So wo's azimuth in pbrt's frame is phi_o = arccos(-h) in [0, pi] (z >= 0)."""
    h = np.asarray(h, float)
    theta_o = np.asarray(theta_o, float)
    phi_o = np.arccos(np.clip(-h, -1, 1))
    c = np.cos(theta_o)
    return np.stack(np.broadcast_arrays(np.sin(theta_o), c * np.cos(phi_o), c * np.sin(phi_o)), axis=-1)


def mitsuba_dict(model) -> dict:
    """Mitsuba 3 ``hair`` plugin dict for a ``bsdfkit.Hair`` (sigma_a form, ext_ior 1, no scale).
    Mitsuba has no ``h`` parameter: it derives h from the direction (see :func:`wo_for_h`)."""
    p = _params(model)
    return {"type": "hair", "sigma_a": {"type": "rgb", "value": [float(x) for x in p["sigma_a"]]},
            "int_ior": p["eta"], "ext_ior": 1.0, "longitudinal_roughness": p["beta_m"],
            "azimuthal_roughness": p["beta_n"], "scale_tilt": p["alpha"]}


def mitsuba_h(wo):
    """The h Mitsuba's ``hair`` derives from a pbrt-frame wo: -wo.y / sqrt(wo.y^2 + wo.z^2)
    (exact for wo.z >= 0; for wo.z < 0 Mitsuba's gamma leaves [-pi/2, pi/2] and it no longer
    matches any pbrt h)."""
    wo = np.asarray(wo, float)
    return -wo[..., 1] / np.sqrt(wo[..., 1] ** 2 + wo[..., 2] ** 2)


def mitsuba_eval_pdf(model, wo, wi):
    """Mitsuba 3 ``hair``'s f (cosine removed) and pdf at pbrt-frame directions: maps both to
    Mitsuba's frame (:func:`to_mitsuba_frame`) and calls ``bsdfkit.testing.mitsuba.eval_pdf``.
    The caller picks wo with ``wo_for_h(model.h, theta_o)`` so Mitsuba's h equals the model's."""
    from . import mitsuba as ref
    return ref.eval_pdf(mitsuba_dict(model), to_mitsuba_frame(wo), to_mitsuba_frame(wi))


def far_field_f(model, wo, wi, n=64):
    """(1/2) int_{-1}^{1} f(h) dh by an n-point Gauss-Legendre rule in gamma = asin h (independent
    of the kernel's code; the kernel's default is also 64 nodes; n = 64 converges to ~1e-6 for beta >= 0.2)."""
    p = dict(_params({**model._params, "h": 0.0}))
    x, w = np.polynomial.legendre.leggauss(n)
    g = x * np.pi / 2
    wk = w * np.cos(g)
    wk = wk / wk.sum()
    out = 0.0
    for gk, wgt in zip(g, wk):
        out = out + wgt * hair_f({**p, "h": float(np.sin(gk))}, wo, wi)
    return out
