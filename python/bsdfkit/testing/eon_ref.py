"""Independent float64 numpy oracle of the EON BRDF (energy-preserving Oren-Nayar; Portsmouth,
Kutz & Hill, "EON: A practical energy-preserving rough diffuse BRDF", JCGT 14(1) 2025,
arXiv:2410.18026; OpenPBR Surface's base diffuse lobe, MaterialX ``oren_nayar_diffuse_bsdf`` with
``energy_compensation=true``). Written from the published formulas, not from bsdfkit's C++:

    f(wo, wi) = f_ss + f_ms
    f_ss      = rho / pi * A * (1 + r * s / t)                  (Fujii's Oren-Nayar, "FON")
    s         = wi . wo - mu_i mu_o,   t = max(mu_i, mu_o) if s > 0 else 1
    A         = 1 / (1 + c1 r),   B = r A,   c1 = 1/2 - 2 / (3 pi),   c2 = 2/3 - 28 / (15 pi)
    E(mu)     = A + B / pi * G(mu)                               (FON directional albedo, rho = 1)
    G(mu)     = S (acos mu - S mu) + 2/3 (S / mu (1 - S^3) - S),   S = sqrt(1 - mu^2)
    Eavg      = A (1 + c2 r)                                     (FON average albedo 2 int E mu dmu)
    rho_ms    = rho^2 Eavg / (1 - rho (1 - Eavg))
    f_ms      = rho_ms / pi * (1 - E(mu_o)) (1 - E(mu_i)) / (1 - Eavg)

r in [0, 1] is OpenPBR's ``base_diffuse_roughness`` (the paper's sigma). At r = 0 this is exactly
Lambert (f_ms = 0; the 0/0 is taken as its limit 0). Two-sided as pbrt-v4's DiffuseBxDF: f = 0
unless wo.z * wi.z > 0; below the surface both cosines are taken as |z|.

Sampling (the paper's section on importance sampling and its listing): with probability
P_u(mu_o, r) = r^0.1 (0.162925 + mu (-0.372058 + mu (0.538233 - 0.290822 mu))) a uniform
hemisphere direction, otherwise the clipped linearly transformed cosine (CLTC) lobe; pdf =
P_u / (2 pi) + (1 - P_u) pdf_CLTC. See :func:`cltc_pdf` for the CLTC density (LTC matrix
M = [[a, 0, b], [0, c, 0], [d, 0, 1]] of the paper's rational fits in (mu_o, r), in the frame whose
x axis is wo's azimuth). bsdfkit's one deviation: ``d`` is clamped to <= 0 (the fit crosses 0 for
mu_o > 0.99989, d <= 0.0035 r there), so the clipped lobe lies exactly in the upper hemisphere.

Everything here is a function of numpy arrays (directions (..., 3), broadcast), float64.
:func:`albedo_quadrature` and :func:`pdf_quadrature` integrate over the hemisphere with a product
Gauss-Legendre rule split at the kinks of the integrand, an independent check of the albedo
formula (white furnace) and of the pdf's normalisation.
"""
from __future__ import annotations

import numpy as np

__all__ = ["C1", "C2", "coeff_a", "fon_albedo", "one_minus_fon_albedo", "fon_albedo_approx", "fon_avg_albedo",
           "rho_ms", "eval_ss", "eval_ms", "eval", "albedo", "lambert", "ltc_coeffs", "uniform_probability",
           "cltc_pdf", "pdf", "pdf_cosine", "sample", "albedo_quadrature", "pdf_quadrature"]

C1 = 0.5 - 2.0 / (3.0 * np.pi)
C2 = 2.0 / 3.0 - 28.0 / (15.0 * np.pi)


def coeff_a(r):
    """Fujii's A(r) = 1 / (1 + c1 r); B = r A."""
    return 1.0 / (1.0 + C1 * np.asarray(r, dtype=np.float64))


def _g(mu):
    """G(mu) of the FON albedo, with S / mu (1 - S^3) rewritten S mu (1 + S + S^2) / (1 + S)
    (1 - S = mu^2 / (1 + S)): no division by mu, exact at mu = 0 (G(0) = pi/2 - 2/3)."""
    mu = np.clip(np.asarray(mu, dtype=np.float64), 0.0, 1.0)
    s = np.sqrt(np.maximum(0.0, 1.0 - mu * mu))
    return s * (np.arccos(mu) - s * mu) + (2.0 / 3.0) * (s * mu * (1.0 + s + s * s) / (1.0 + s) - s)


def fon_albedo(mu, r):
    """Directional albedo E(mu) of the FON lobe with rho = 1 (closed form, the paper's "exact")."""
    r = np.asarray(r, dtype=np.float64)
    return coeff_a(r) * (1.0 + r * _g(mu) / np.pi)


def one_minus_fon_albedo(mu, r):
    """1 - E(mu) = r (c1 - G(mu)/pi) / (1 + c1 r), without cancellation (0 at r = 0)."""
    r = np.asarray(r, dtype=np.float64)
    return r * (C1 - _g(mu) / np.pi) * coeff_a(r)


def fon_albedo_approx(mu, r):
    """The paper's fast polynomial fit of E(mu) (G/pi as a quartic in 1 - mu); not used by eval."""
    r = np.asarray(r, dtype=np.float64)
    m = 1.0 - np.asarray(mu, dtype=np.float64)
    g_over_pi = m * (0.0571085289 + m * (0.491881867 + m * (-0.332181442 + m * 0.0714429953)))
    return (1.0 + r * g_over_pi) / (1.0 + C1 * r)


def fon_avg_albedo(r):
    """Average (cosine-weighted hemispherical) albedo of FON, rho = 1: A (1 + c2 r)."""
    r = np.asarray(r, dtype=np.float64)
    return coeff_a(r) * (1.0 + C2 * r)


def _one_minus_avg(r):
    """1 - Eavg = (c1 - c2) r / (1 + c1 r), without cancellation."""
    r = np.asarray(r, dtype=np.float64)
    return (C1 - C2) * r * coeff_a(r)


def rho_ms(rho, r):
    """Multiple-scattering albedo rho^2 Eavg / (1 - rho (1 - Eavg)) (per channel)."""
    rho = np.asarray(rho, dtype=np.float64)
    e = fon_avg_albedo(r)
    return rho * rho * e / (1.0 - rho * (1.0 - e))


def _frame(wo, wi):
    """(mu_o, mu_i, s, same) with two-sided folding: both below -> |z|; s = x_o x_i + y_o y_i."""
    wo = np.asarray(wo, dtype=np.float64)
    wi = np.asarray(wi, dtype=np.float64)
    same = wo[..., 2] * wi[..., 2] > 0
    mu_o, mu_i = np.abs(wo[..., 2]), np.abs(wi[..., 2])
    s = wo[..., 0] * wi[..., 0] + wo[..., 1] * wi[..., 1]   # = wi . wo - mu_i mu_o (also when both flipped)
    return mu_o, mu_i, s, same


def _rgb(rho):
    rho = np.asarray(rho, dtype=np.float64)
    return np.broadcast_to(rho, (3,)) if rho.ndim == 0 else rho


def eval_ss(wo, wi, rho, r):
    """Single-scattering FON lobe rho/pi A (1 + r s/t), (..., 3); 0 unless same hemisphere."""
    mu_o, mu_i, s, same = _frame(wo, wi)
    with np.errstate(divide="ignore", invalid="ignore"):
        s_over_t = np.where(s > 0, s / np.maximum(mu_i, mu_o), s)
    v = coeff_a(r) * (1.0 + r * s_over_t) / np.pi
    return np.where(same, v, 0.0)[..., None] * _rgb(rho)


def eval_ms(wo, wi, rho, r):
    """Multiple-scattering term rho_ms/pi (1 - E_o)(1 - E_i)/(1 - Eavg), (..., 3); exactly 0 at r = 0."""
    mu_o, mu_i, _, same = _frame(wo, wi)
    r = float(r)
    if r == 0.0:
        return np.zeros(np.shape(mu_o) + (3,))
    k = one_minus_fon_albedo(mu_o, r) * one_minus_fon_albedo(mu_i, r) / _one_minus_avg(r) / np.pi
    return np.where(same, k, 0.0)[..., None] * rho_ms(_rgb(rho), r)


def eval(wo, wi, rho, r):
    """f(wo, wi) of EON (cosine excluded), (..., 3)."""
    return eval_ss(wo, wi, rho, r) + eval_ms(wo, wi, rho, r)


def albedo(mu_o, rho, r):
    """Closed-form directional albedo of EON: rho E(mu) + rho_ms (1 - E(mu)), (..., 3)."""
    e = fon_albedo(mu_o, r)[..., None]
    rho = _rgb(rho)
    return rho * e + rho_ms(rho, r) * (1.0 - e)


def lambert(wo, wi, rho):
    """rho / pi where wo, wi are on the same side, else 0, (..., 3)."""
    _, _, _, same = _frame(wo, wi)
    return np.where(same, 1.0 / np.pi, 0.0)[..., None] * _rgb(rho)


# ------------------------------------------------------------------------------- sampling

def ltc_coeffs(mu, r):
    """(a, b, c, d) of the LTC matrix M = [[a, 0, b], [0, c, 0], [d, 0, 1]] (the paper's rational
    fits in (mu_o, r)); d clamped to <= 0 (bsdfkit; see the module docstring)."""
    mu = np.clip(np.asarray(mu, dtype=np.float64), 0.0, 1.0)
    r = np.asarray(r, dtype=np.float64)
    a = 1.0 + r * (0.303392 + (-0.518982 + 0.111709 * mu) * mu + (-0.276266 + 0.335918 * mu) * r)
    b = r * (-1.16407 + 1.15859 * mu + (0.150815 - 0.150105 * mu) * r) / (mu * mu * mu - 1.43545)
    c = 1.0 + (0.20013 + (-0.506373 + 0.261777 * mu) * mu) * r
    d = r * (0.540852 + (-1.01625 + 0.475392 * mu) * mu) / (-1.0743 + mu * (0.0725628 + mu))
    return a, b, c, np.minimum(d, 0.0)


def uniform_probability(mu, r):
    """P_u: probability of the uniform-hemisphere component of the sampling mixture."""
    mu = np.clip(np.asarray(mu, dtype=np.float64), 0.0, 1.0)
    return np.power(np.asarray(r, dtype=np.float64), 0.1) * (
        0.162925 + mu * (-0.372058 + (0.538233 - 0.290822 * mu) * mu))


def _ltc_basis(wo):
    """(X, Y) of the LTC frame: X = wo's azimuth direction (x axis if wo is the normal), Y = z x X."""
    wo = np.asarray(wo, dtype=np.float64)
    l2 = wo[..., 0] ** 2 + wo[..., 1] ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = np.where(l2 > 0, 1.0 / np.sqrt(l2), 0.0)
    xx = np.where(l2 > 0, wo[..., 0] * inv, 1.0)
    xy = np.where(l2 > 0, wo[..., 1] * inv, 0.0)
    return xx, xy


def cltc_pdf(wo, wi, r):
    """Density of the CLTC lobe, both in the upper hemisphere (folded): with u = M^-1 wi (LTC
    frame), pdf = max(u_z, 0) / (pi s_c det M |u|^4), det M = c (a - b d), s_c = (1 + 1/sqrt(1 + d^2)) / 2
    (the clipped disk's area over pi). Written with adj(M) = det(M) M^-1 as the paper does."""
    wo = np.asarray(wo, dtype=np.float64)
    wi = np.asarray(wi, dtype=np.float64)
    xx, xy = _ltc_basis(wo)
    lx = wi[..., 0] * xx + wi[..., 1] * xy
    ly = -wi[..., 0] * xy + wi[..., 1] * xx
    lz = np.abs(wi[..., 2])
    a, b, c, d = ltc_coeffs(np.abs(wo[..., 2]), r)
    det = c * (a - b * d)
    hx, hy, hz = c * (lx - b * lz), (a - b * d) * ly, -c * (d * lx - a * lz)   # adj(M) wi
    l2 = hx * hx + hy * hy + hz * hz
    sc = 0.5 * (1.0 + 1.0 / np.sqrt(d * d + 1.0))
    return (det / l2) ** 2 * np.maximum(hz, 0.0) / (np.pi * sc)


def pdf(wo, wi, r):
    """Solid-angle density of the paper's sampler (uniform + CLTC mixture); 0 unless same side."""
    wo = np.asarray(wo, dtype=np.float64)
    wi = np.asarray(wi, dtype=np.float64)
    pu = uniform_probability(np.abs(wo[..., 2]), r)
    p = pu / (2.0 * np.pi) + (1.0 - pu) * cltc_pdf(wo, wi, r)
    return np.where(wo[..., 2] * wi[..., 2] > 0, p, 0.0)


def pdf_cosine(wo, wi):
    """|cos theta_i| / pi on wo's side (the simplest unbiased alternative sampler)."""
    wo = np.asarray(wo, dtype=np.float64)
    wi = np.asarray(wi, dtype=np.float64)
    return np.where(wo[..., 2] * wi[..., 2] > 0, np.abs(wi[..., 2]) / np.pi, 0.0)


def sample(wo, r, uc, u):
    """The paper's sampler, vectorized: ``uc`` (n,) picks the component (uc < P_u: uniform), ``u``
    (n, 2) the direction. Returns (wi (n, 3), pdf (n,)); wi on wo's side (two-sided)."""
    wo = np.asarray(wo, dtype=np.float64)
    uc = np.asarray(uc, dtype=np.float64)
    u = np.asarray(u, dtype=np.float64)
    wo = np.broadcast_to(wo, uc.shape + (3,))
    mu = np.abs(wo[..., 2])
    pu = uniform_probability(mu, r)
    # uniform hemisphere: z = u1
    st = np.sqrt(np.maximum(0.0, 1.0 - u[..., 0] ** 2))
    ph = 2.0 * np.pi * u[..., 1]
    w_uni = np.stack([st * np.cos(ph), st * np.sin(ph), u[..., 0]], -1)
    # CLTC: a point uniform in the clipped disk {x <= vz sqrt(1 - y^2)}, lifted, then M
    a, b, c, d = ltc_coeffs(mu, r)
    rad, ph = np.sqrt(u[..., 0]), 2.0 * np.pi * u[..., 1]
    x, y = rad * np.cos(ph), rad * np.sin(ph)
    vz = 1.0 / np.sqrt(d * d + 1.0)
    sc = 0.5 * (1.0 + vz)
    x = -((1.0 - sc) * np.sqrt(np.maximum(0.0, 1.0 - y * y)) + sc * x)
    z = np.sqrt(np.maximum(0.0, 1.0 - x * x - y * y))
    v = np.stack([a * x + b * z, c * y, d * x + z], -1)
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    xx, xy = _ltc_basis(wo)
    w_ltc = np.stack([v[..., 0] * xx - v[..., 1] * xy, v[..., 0] * xy + v[..., 1] * xx, v[..., 2]], -1)
    wi = np.where((uc < pu)[..., None], w_uni, w_ltc)
    wi[..., 2] = np.where(wo[..., 2] < 0, -wi[..., 2], wi[..., 2])
    return wi, pdf(wo, wi, r)


# ------------------------------------------------------------------------------- quadrature

def _gl(n, lo, hi):
    x, w = np.polynomial.legendre.leggauss(n)
    return 0.5 * (hi - lo) * x + 0.5 * (hi + lo), 0.5 * (hi - lo) * w


def _hemisphere_rule(mu_o, n_mu, n_phi):
    """Nodes (mu_i, phi relative to wo's azimuth) and weights of a product Gauss-Legendre rule over
    the hemisphere, in (theta, phi) (d omega = sin theta d theta d phi: smooth at the normal, where
    sqrt(1 - mu^2) is not), split where f_FON has kinks: theta_i = theta_o (t = max) and
    cos phi = 0 (the sign of s)."""
    th_o = float(np.arccos(np.clip(mu_o, 0.0, 1.0)))
    ths, wth = [], []
    for lo, hi in ((0.0, th_o), (th_o, 0.5 * np.pi)):
        if hi > lo:
            x, w = _gl(n_mu, lo, hi)
            ths.append(x)
            wth.append(w * np.sin(x))
    th, wt = np.concatenate(ths), np.concatenate(wth)
    phs, wph = [], []
    for lo, hi in ((-0.5 * np.pi, 0.5 * np.pi), (0.5 * np.pi, 1.5 * np.pi)):
        x, w = _gl(n_phi, lo, hi)
        phs.append(x)
        wph.append(w)
    ph, wp = np.concatenate(phs), np.concatenate(wph)
    return np.cos(th)[:, None], ph[None, :], (wt[:, None] * wp[None, :])


def _dirs(mu_o, mu, ph, phi_o):
    st = np.sqrt(np.maximum(0.0, 1.0 - mu * mu))
    wi = np.stack(np.broadcast_arrays(st * np.cos(ph + phi_o), st * np.sin(ph + phi_o), mu), -1)
    so = np.sqrt(max(0.0, 1.0 - mu_o * mu_o))
    wo = np.array([so * np.cos(phi_o), so * np.sin(phi_o), mu_o])
    return wo, wi


def albedo_quadrature(wo, rho, r, n_mu=64, n_phi=64):
    """Directional albedo int f(wo, wi) |cos theta_i| d wi by quadrature (independent of the closed
    form :func:`albedo`), (3,). ``wo`` one direction (either side). Error ~1e-15 at the defaults."""
    wo = np.asarray(wo, dtype=np.float64)
    mu_o = abs(float(wo[2]))
    phi_o = float(np.arctan2(wo[1], wo[0]))
    mu, ph, w = _hemisphere_rule(mu_o, n_mu, n_phi)
    wo_u, wi = _dirs(mu_o, mu, ph, phi_o)
    f = eval(wo_u, wi, rho, r)
    return np.einsum("ijk,ij->k", f * mu[..., None], w)


def pdf_quadrature(wo, r, n_mu=256, n_phi=256, pdf_fn=None):
    """int pdf(wo, wi) d wi over wo's hemisphere by quadrature; ``pdf_fn(wo, wi)`` (default: the
    reference :func:`pdf`). The CLTC density has a kink along the edge of its support (u_z = 0),
    which the rule does not follow: error ~1e-5 at the defaults."""
    wo = np.asarray(wo, dtype=np.float64)
    mu_o = abs(float(wo[2]))
    phi_o = float(np.arctan2(wo[1], wo[0]))
    mu, ph, w = _hemisphere_rule(mu_o, n_mu, n_phi)
    wo_u, wi = _dirs(mu_o, mu, ph, phi_o)
    if wo[2] < 0:
        wo_u = wo_u * np.array([1.0, 1.0, -1.0])
        wi = wi * np.array([1.0, 1.0, -1.0])
    fn = pdf_fn if pdf_fn is not None else (lambda a, b: pdf(a, b, r))
    p = np.asarray(fn(wo_u, np.ascontiguousarray(wi.reshape(-1, 3))), dtype=np.float64)
    return float(np.sum(np.reshape(p, w.shape) * w))
