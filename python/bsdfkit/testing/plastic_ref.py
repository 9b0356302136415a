"""Float64 Dr.Jit restatement of ``Plastic`` (Mitsuba 3's ``plastic`` / ``roughplastic`` inside
``twosided``), written from the formulas, not from the C++:

    f(wo, wi) = Ks F(o . h) D(h) G(o, i) / (4 cos_o cos_i)                    [rough coat only]
              + R / (1 - Fdr) T(cos_o) T(cos_i) / (pi eta^2)     [nonlinear: R / (1 - R Fdr)]

(Weidlich & Wilkie 2007's coating over a Lambertian base, as Mitsuba's plastic.cpp /
roughplastic.cpp define it). Smooth coat (alpha < 1e-3): T = 1 - F_dielectric(cos, eta) and Fdr =
Mitsuba's fitted diffuse Fresnel reflectance of 1/eta (Egan & Hilgeman 1973 for an argument < 1,
d'Eon & Irving 2011's polynomial in 1/argument otherwise). Rough coat: T is the linear interpolant
of a 64-entry table T_j = T(max(1e-6, j / 63)) and Fdr = 2 / 64 sum_j R_int(mu_j) mu_j, where
T(mu) and R_int(mu) (the directional transmittance from outside and the directional reflectance
from inside, relative IOR 1/eta) are integrated, as Mitsuba defines them, with a Gauss-Legendre
product rule (32^2 nodes when the relative IOR of the side is > 1, 128^2 otherwise; numpy's
``leggauss``) over the unit square pushed through the GGX visible-normal warp of Heitz & d'Eon
2014 with the concentric-disk slope sampler (Mitsuba's ``sample_visible_11``); the integrand is
G1(w_out, m) (1 - F(w . m)) for the refracted, F(w . m) for the reflected direction, G1 the
Smith GGX term with the back-facing rule (0 when w.m and w.z differ in sign). D, G: the
Trowbridge-Reitz distribution and Smith masking (``correlated`` or ``separable``) of
``drjit_models``. alpha is floored at 1e-4. Two-sided: a wo below the surface flips both
directions.

Parameters may be numbers or Dr.Jit AD leaves: every quantity (the tables included) is computed
from them with Dr.Jit, so forward-mode AD (``bsdfkit.testing.drjit_grad.plastic_grad``) gives
the derivative of the model as it is defined, through its quadratures.
"""
from __future__ import annotations

import numpy as np

from . import drjit_models as dm
from .layered_analytic_ref import _is_dr, _num, _rgb3

__all__ = ["plastic_f", "plastic_tables", "fresnel_diffuse_reflectance"]

SMOOTH_ALPHA = 1e-3
MIN_ALPHA = 1e-4
RES = 64


def _value(x):
    return float(x.numpy()[0]) if _is_dr(x) else float(x)


def fresnel_diffuse_reflectance(eta):
    """Mitsuba's fit of the hemispherical average of F for light from the side of relative IOR eta."""
    ie = 1.0 / eta
    if _value(eta) < 1.0:   # Egan & Hilgeman 1973
        return 0.0636 * ie + eta * (eta * -1.4399 + 0.7099) + 0.6681
    # d'Eon & Irving 2011, a polynomial in 1/eta
    return 0.919317 + ie * (-3.4793 + ie * (6.75335 + ie * (-7.80989 + ie * (4.98554 + ie * -1.36881))))


def _disk_concentric(ux, uy):
    """Shirley & Chiu 1997's concentric map of [0, 1]^2 to the unit disk."""
    dr, _ = dm._bk()
    x, y = 2.0 * ux - 1.0, 2.0 * uy - 1.0
    steep = dr.abs(x) < dr.abs(y)
    r = dr.select(steep, y, x)
    q = dr.select(steep, x, y)
    phi = (np.pi / 4) * q / dr.select(r == 0, 1.0, r)
    phi = dr.select(steep, np.pi / 2 - phi, phi)
    return r * dr.cos(phi), r * dr.sin(phi)


def _visible_normal(alpha, w, ux, uy):
    """GGX normal m distributed as D_w(m) (Heitz & d'Eon 2014): stretch w by alpha, sample the
    slope of the alpha = 1 distribution seen at the stretched elevation (disk variant), rotate to
    the stretched azimuth, unstretch, normalize."""
    dr, _ = dm._bk()
    sx, sy, sz = alpha * w[0], alpha * w[1], w[2]
    inv = 1.0 / dr.sqrt(sx * sx + sy * sy + sz * sz)
    sx, sy, sz = sx * inv, sy * inv, sz * inv
    sin_t = dm._safe_sqrt(1.0 - sz * sz)
    pole = sin_t == 0
    st = dr.select(pole, 1.0, sin_t)
    cphi = dr.select(pole, 1.0, dm._clamp(sx / st, -1.0, 1.0))
    sphi = dr.select(pole, 0.0, dm._clamp(sy / st, -1.0, 1.0))
    cos_t = sz
    px, py = _disk_concentric(ux, uy)
    h = 0.5 * (1.0 + cos_t)
    py = (1.0 - h) * dm._safe_sqrt(1.0 - px * px) + h * py
    pz = dm._safe_sqrt(1.0 - px * px - py * py)
    norm = 1.0 / (sin_t * py + cos_t * pz)
    slope_x, slope_y = (cos_t * py - sin_t * pz) * norm, px * norm
    mx = (cphi * slope_x - sphi * slope_y) * alpha
    my = (sphi * slope_x + cphi * slope_y) * alpha
    n = 1.0 / dr.sqrt(mx * mx + my * my + 1.0)
    return (-mx * n, -my * n, n)


def _smith_g1_backfacing(alpha, v, m):
    """Smith G1 of GGX, 2 / (1 + sqrt(1 + alpha^2 tan^2)), 0 when v.m and v.z differ in sign."""
    dr, _ = dm._bk()
    xy = (alpha * v[0]) ** 2 + (alpha * v[1]) ** 2
    g = dr.select(xy == 0, 1.0, 2.0 / (1.0 + dr.sqrt(1.0 + xy / (v[2] * v[2]))))
    return dr.select(dm._dot(v, m) * v[2] <= 0, 0.0, g)


def _albedo_table(alpha, eta, refract):
    """The 64 directional albedos (transmittance from outside, or reflectance from the side of
    relative IOR eta) at mu_j = max(1e-6, j / 63), as a Dr.Jit array of width 64."""
    dr, F = dm._bk()
    n = 32 if _value(eta) > 1.0 else 128
    x, w = np.polynomial.legendre.leggauss(n)
    mu = np.maximum(1e-6, np.arange(RES) / (RES - 1.0))
    # layout (j, a, b): u = ((x_b + 1) / 2, (x_a + 1) / 2), weight w_a w_b / 4
    ux = np.tile(0.5 * x + 0.5, RES * n)
    uy = np.tile(np.repeat(0.5 * x + 0.5, n), RES)
    wt = np.tile(np.outer(w, w).ravel() * 0.25, RES)
    muj = np.repeat(mu, n * n)
    wv = (F(np.sqrt(1.0 - muj * muj)), F(np.zeros_like(muj)), F(muj))
    m = _visible_normal(alpha, wv, F(ux), F(uy))
    c = dm._dot(wv, m)
    fr = dm._fr_dielectric(c, eta)
    if refract:
        ct = -dm._safe_sqrt(1.0 - (1.0 - c * c) / (eta * eta))   # Snell through m
        k = c / eta + ct
        wt_dir = (m[0] * k - wv[0] / eta, m[1] * k - wv[1] / eta, m[2] * k - wv[2] / eta)
        val = dr.select(wt_dir[2] * wv[2] >= 0, 0.0, _smith_g1_backfacing(alpha, wt_dir, m) * (1.0 - fr))
    else:
        wr = (2.0 * c * m[0] - wv[0], 2.0 * c * m[1] - wv[1], 2.0 * c * m[2] - wv[2])
        val = dr.select(wr[2] <= 0, 0.0, _smith_g1_backfacing(alpha, wr, m) * fr)
    return dr.block_sum(val * F(wt), n * n)


def plastic_tables(alpha, eta):
    """(T: Dr.Jit array of the 64 transmittances, Fdr) of a rough coat (alpha floored at 1e-4)."""
    dr, F = dm._bk()
    alpha, eta = _num(alpha), _num(eta)
    alpha = dr.select(alpha < MIN_ALPHA, MIN_ALPHA, alpha)
    T = _albedo_table(alpha, eta, True)
    mu = F(np.maximum(1e-6, np.arange(RES) / (RES - 1.0)))
    R = _albedo_table(alpha, 1.0 / eta, False)
    fdr = 2.0 * dr.sum(R * mu) / RES
    return T, fdr


def _lerp_table(T, cos):
    dr, _ = dm._bk()
    x = cos * (RES - 1)
    fi = dm._clamp(dr.floor(x), 0.0, RES - 2.0)
    idx = dr.int32_array_t(type(fi))(fi)
    t0, t1 = dr.gather(type(T), T, idx), dr.gather(type(T), T, idx + 1)
    u = x - fi
    return (1.0 - u) * t0 + u * t1


@dm._outputs((3,))
def plastic_f(p, wo, wi):
    """f (..., 3) of ``Plastic`` with parameters ``p`` (attributes as the Python model's
    ``_params``; numbers or Dr.Jit AD leaves)."""
    dr, F = dm._bk()
    batch, o0, i0 = dm._direction_planes(wo, wi)
    eta, alpha = _num(p.eta), _num(p.alpha)
    R, Ks = _rgb3(p.reflectance), _rgb3(p.specular_reflectance)
    rough = _value(alpha) >= SMOOTH_ALPHA
    s = dm._sel(o0[2] < 0, -1.0, 1.0)
    o, i = dm._scale(o0, s), dm._scale(i0, s)
    active = (o[2] > 0) & (i[2] > 0)
    if rough:
        T, fdr = plastic_tables(alpha, eta)
        To, Ti = _lerp_table(T, o[2]), _lerp_table(T, i[2])
    else:
        fdr = fresnel_diffuse_reflectance(1.0 / eta)
        To, Ti = 1.0 - dm._fr_dielectric(o[2], eta), 1.0 - dm._fr_dielectric(i[2], eta)
    base = [R[c] / (1.0 - (R[c] * fdr if p.nonlinear else fdr)) / (np.pi * eta * eta) for c in range(3)]
    f = [base[c] * To * Ti for c in range(3)]
    if rough:
        a = dr.select(alpha < MIN_ALPHA, MIN_ALPHA, alpha)
        h = dm._add(o, i)
        l2 = dm._dot(h, h)
        ok = l2 > 0
        h = dm._scale(h, 1.0 / dr.sqrt(dm._sel(ok, l2, 1.0)))
        spec = dm._D(a, a, h) * dm._G(a, a, o, i, p.masking) * dm._fr_dielectric(dm._dot(o, h), eta) \
            / (4.0 * o[2] * i[2])
        spec = dm._sel(ok, spec, 0.0)
        f = [f[c] + Ks[c] * spec for c in range(3)]
    f = [dm._sel(active, fc, 0.0) for fc in f]
    return dm._out3(batch, f)
