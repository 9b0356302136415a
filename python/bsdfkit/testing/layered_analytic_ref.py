"""Float64 Dr.Jit restatement of the analytic layered approximation (``CoatedDiffuse`` /
``CoatedConductor`` with ``method="analytic"``), written from its formulas, not from the C++:

    f(wo, wi) = f_coat(wo, wi)
              + T(wo) T(wi) / eta^2 [ M f_base(wo', wi') a + albedo p_HG(wo' . wi', g) (1 - a) / (cos_o' + cos_i') ]

f_coat: the coating's rough GGX reflection D G F / (4 cos_o cos_i) (Weidlich & Wilkie 2007, the
top layer; 0 for a smooth coat, a delta); T = 1 - F_dielectric at the macro normal; wo', wi':
the directions refracted by the macro normal (Snell); a = exp(-d (1/cos_o' + 1/cos_i'))
(Beer-Lambert, sigma_t = 1); M = 1 / (1 - rho_b Fdr_int t_d^2), the internal-reflection sum with
rho_b the base's cosine-weighted albedo (R for a diffuse base, 2 int F_complex(mu) mu dmu for a
metal, roughness neglected), Fdr_int = 2 int F_dielectric(mu, 1/eta) mu dmu (1 below the
critical cosine) and t_d = 2 int exp(-d / mu) mu dmu; the last term is Hanrahan & Krueger's
single scattering (1993, eq. 21) with Henyey-Greenstein (pbrt-v4's convention). The metal's IOR
is relative to the coating (eta_metal / eta, k_metal / eta). The three hemispherical integrals
are, as the model defines them, 64-node Gauss-Legendre rules (here numpy's ``leggauss``).
Two-sided: a wo below the surface flips both directions. Parameters may be numbers or Dr.Jit AD
leaves (``bsdfkit.testing.drjit_grad.coated_analytic_grad``).
"""
from __future__ import annotations

import numpy as np

from . import drjit_models as dm

__all__ = ["coated_f"]

FLT_MIN = float(np.finfo(np.float32).tiny)   # the thickness floor (a zero-thickness slab is a limit)
G_MAX = 0.99                                 # |g| clamp of the phase function
N_GL = 64


def _is_dr(x):
    return hasattr(x, "numpy") and not isinstance(x, np.ndarray)


def _num(x):
    """A parameter as a Float64 array (width 1 unless it is an AD leaf already): Python floats
    would make dr.select of two constants a single-precision array."""
    return x if _is_dr(x) else dm._bk()[1](float(x))


def _rgb3(x):
    if isinstance(x, (list, tuple)) and any(_is_dr(v) for v in x):
        return [_num(v) for v in x]
    return [_num(v) for v in np.broadcast_to(np.asarray(x, dtype=np.float64), (3,))]


def _cos_mean(g, a=0.0):
    """2 int_0^1 g(mu) mu dmu with g = 1 on [0, a]: a^2 + the Gauss-Legendre rule on [a, 1]."""
    dr, F = dm._bk()
    x, w = np.polynomial.legendre.leggauss(N_GL)
    X, W = F(x), F(w)
    mu = a + (1.0 - a) * 0.5 * (X + 1.0)
    return a * a + dr.sum(2.0 * g(mu) * mu * 0.5 * (1.0 - a) * W)


def _hg(cos_t, g):
    # Henyey & Greenstein 1941: (1 - g^2) / (4 pi (1 + g^2 + 2 g cos)^1.5) (pbrt-v4's sign convention)
    dr, _ = dm._bk()
    d = 1.0 + g * g + 2.0 * g * cos_t
    return (1.0 - g * g) / (4.0 * np.pi * d * dm._safe_sqrt(d))


def _ggx_reflection(ax, ay, o, i, masking, fresnel):
    """D G F(|o . wm|) / (4 cos_o cos_i) with wm = normalize(o + i) (both upper), 0 for smooth alphas."""
    dr, F = dm._bk()
    ax, ay = (a if _is_dr(a) else F(float(a)) for a in (ax, ay))   # array masks, not Python bools
    smooth, ax, ay = dm._max_alpha_rules(ax, ay)
    wm = dm._add(o, i)
    len2 = dm._dot(wm, wm)
    ok = ~smooth & (len2 > 0) & (o[2] * i[2] > 0)
    wm = dm._scale(wm, 1.0 / dr.sqrt(dm._sel(ok, len2, 1.0)))
    base = dm._D(ax, ay, wm) * dm._G(ax, ay, o, i, masking) / (4.0 * o[2] * i[2])
    F = fresnel(dm._abs(dm._dot(o, wm)))
    if isinstance(F, list):
        return [dm._sel(ok, base * Fc, 0.0) for Fc in F]
    return dm._sel(ok, base * F, 0.0)


def _refracted(w, eta):
    inv = 1.0 / eta
    return (w[0] * inv, w[1] * inv, dm._safe_sqrt(1.0 - (1.0 - w[2] * w[2]) * inv * inv))


@dm._outputs((3,))
def coated_f(p, family, wo, wi):
    """f (..., 3) of the analytic layered model with parameters ``p`` (attributes as the Python
    model's ``_params``), ``family`` "CoatedDiffuse" or "CoatedConductor"."""
    dr, F = dm._bk()
    batch, o0, i0 = dm._direction_planes(wo, wi)
    conductor = family == "CoatedConductor"
    eta = _num(p.interface_eta if conductor else p.eta)
    ax, ay = ((_num(p.interface_alpha_x), _num(p.interface_alpha_y)) if conductor
              else (_num(p.alpha_x), _num(p.alpha_y)))
    d = _num(p.thickness)
    d = dm._sel(d > FLT_MIN, d, FLT_MIN)
    g = dm._clamp(_num(p.g), -G_MAX, G_MAX)
    albedo = _rgb3(p.albedo)
    has_albedo = any(float(a.numpy()[0]) != 0 for a in albedo)
    # the hemispherical integrals
    inv_eta = 1.0 / eta
    a_c = dm._sel(inv_eta < 1.0, dm._safe_sqrt(1.0 - inv_eta * inv_eta), 0.0)
    fdr_int = _cos_mean(lambda mu: dm._fr_dielectric(mu, inv_eta), a_c)
    td = _cos_mean(lambda mu: dr.exp(-d / mu))
    if conductor:
        ce = [e / eta for e in _rgb3(p.conductor_eta)]
        ck = [k / eta for k in _rgb3(p.conductor_k)]
        rho = [_cos_mean(lambda mu, c=c: dm._fr_complex(mu, ce[c], ck[c])) for c in range(3)]
    else:
        R = _rgb3(p.reflectance)
        rho = R
    M = [1.0 / (1.0 - rho[c] * fdr_int * td * td) for c in range(3)]
    # geometry: two-sided flip, refraction, absorption
    s = dm._sel(o0[2] < 0, -1.0, 1.0)
    o, i = dm._scale(o0, s), dm._scale(i0, s)
    active = (o[2] > 0) & (i[2] > 0)
    To = 1.0 - dm._fr_dielectric(o[2], eta)
    Ti = 1.0 - dm._fr_dielectric(i[2], eta)
    op, ip = _refracted(o, eta), _refracted(i, eta)
    prod = op[2] * ip[2]
    a = dm._sel(prod > 0, dr.exp(-d * (op[2] + ip[2]) / dm._sel(prod > 0, prod, 1.0)), 0.0)
    if conductor:
        fb = _ggx_reflection(_num(p.conductor_alpha_x), _num(p.conductor_alpha_y), op, ip, p.masking,
                             lambda c: [dm._fr_complex(c, ce[k], ck[k]) for k in range(3)])
    else:
        fb = [R[c] / np.pi + 0.0 * o[2] for c in range(3)]
    inner = [fb[c] * M[c] * a for c in range(3)]
    if has_albedo:
        cs = op[2] + ip[2]
        ss = dm._sel(cs > 0, _hg(dm._dot(op, ip), g) * (1.0 - a) / dm._sel(cs > 0, cs, 1.0), 0.0)
        inner = [inner[c] + albedo[c] * ss for c in range(3)]
    coat = _ggx_reflection(ax, ay, o, i, p.masking, lambda c: dm._fr_dielectric(c, eta))
    coat = dm._sel(eta != 1.0, coat, 0.0)
    tt = To * Ti / (eta * eta)
    f = [dm._sel(active, inner[c] * tt + coat, 0.0) for c in range(3)]
    return dm._out3(batch, f)
