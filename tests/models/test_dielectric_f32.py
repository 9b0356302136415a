"""float32 accuracy of the rough dielectric (issue 10): the float32 kernel against the float64
kernel on the same (float32-representable) direction pairs.

Well-conditioned pairs are those where f's relative condition number is O(1): both cosines,
both microfacet cosines |wo.wm|, |wi.wm| and the refraction cosine cos(theta_t) at the
microfacet are >= 0.1 in magnitude (|cos^2 theta_t| >= 0.1), and for transmission the
generalized half vector |wi etap + wo| / etap >= 0.1. What remains outside that set is
conditioning, not arithmetic: near the microfacet's critical angle dF/dcos ~ 1 / cos(theta_t)
(and T -> 0 like cos(theta_t)), so a float32 rounding of wo.wm (~6e-8) becomes a relative error
~6e-8 / cos^2(theta_t) in f (measured p99.9: 1.5e-4 for cos^2 theta_t in [1e-3, 1e-2), 1.2e-5
in [1e-2, 0.1)); near the back-facing cut (wi.wm -> 0) f -> 0 and its relative error is unbounded.
"""
import numpy as np
import pytest

import bsdfkit as bk


def _pairs(n, seed):
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(2, n, 3))
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    return v[0].astype(np.float32), v[1].astype(np.float32)


def _well_conditioned(wo, wi, eta):
    co, ci = wo[:, 2], wi[:, 2]
    refl = co * ci > 0
    etap = np.where(refl, 1.0, np.where(co > 0, eta, 1 / eta))
    h = wi * etap[:, None] + wo
    hl = np.linalg.norm(h, axis=1)
    h = h / hl[:, None] * np.sign(h[:, 2:3])
    c = np.sum(wo * h, 1)
    e = np.where(c > 0, eta, 1 / eta)
    cos2_t = 1 - (1 - c * c) / e ** 2
    good = ((np.abs(co) >= 0.1) & (np.abs(ci) >= 0.1) & (np.abs(c) >= 0.1) & (np.abs(np.sum(wi * h, 1)) >= 0.1)
            & (np.abs(cos2_t) >= 0.1) & (refl | (hl / etap >= 0.1)))
    return good, refl


@pytest.mark.parametrize("eta", [1.5, 1 / 1.5, 1.33, 2.4])
@pytest.mark.parametrize("mode", [bk.TransportMode.Radiance, bk.TransportMode.Importance])
def test_float32_eval_matches_float64_when_well_conditioned(eta, mode):
    m = bk.Dielectric(eta, alpha=1.0)
    wo32, wi32 = _pairs(300_000, 11)
    wo, wi = wo32.astype(np.float64), wi32.astype(np.float64)
    f64 = m.eval(wo, wi, mode=mode)[:, 0]
    f32 = m.eval(wo32, wi32, mode=mode)[:, 0].astype(np.float64)
    good, refl = _well_conditioned(wo, wi, eta)
    good &= f64 > 0
    assert good.sum() > 100_000 and (good & ~refl).sum() > 10_000
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = np.abs(f32 - f64) / f64
    for sel in (good & refl, good & ~refl):
        assert np.quantile(rel[sel], 0.999) <= 1e-5
        assert rel[sel].max() <= 1e-4
    # and the pdf, whose transmission Jacobian is |wi.wm| etap^2 / |h|^2
    p64 = m.pdf(wo, wi, mode=mode)
    p32 = m.pdf(wo32, wi32, mode=mode).astype(np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        relp = np.abs(p32 - p64) / p64
    assert np.quantile(relp[good], 0.999) <= 1e-5


def test_transmittance_closed_form_matches_one_minus_reflectance():
    """The complement T = 1 - F used by the transmission lobe (its own closed form, no
    cancellation near the critical angle) against 1 - F from the Fresnel equations in float64."""
    m = bk.Dielectric(1.5, alpha=0.5)
    wo32, wi32 = _pairs(100_000, 3)
    wo, wi = wo32.astype(np.float64), wi32.astype(np.float64)
    trans = wo[:, 2] * wi[:, 2] < 0
    wo, wi = wo[trans], wi[trans]
    f = m.eval(wo, wi)[:, 0]
    # Walter 2007 eq. 21 written out in numpy with T = 1 - F from the textbook F
    eta = 1.5
    etap = np.where(wo[:, 2] > 0, eta, 1 / eta)
    h = wi * etap[:, None] + wo
    h /= np.linalg.norm(h, axis=1, keepdims=True)
    h *= np.sign(h[:, 2:3])
    c = np.sum(wo * h, 1)
    e = np.where(c > 0, eta, 1 / eta)
    ca = np.abs(c)
    s2 = (1 - ca ** 2) / e ** 2
    ct = np.sqrt(np.maximum(0, 1 - s2))
    rpa = (e * ca - ct) / (e * ca + ct)
    rpe = (ca - e * ct) / (ca + e * ct)
    F = np.where(s2 >= 1, 1.0, (rpa ** 2 + rpe ** 2) / 2)
    a = 0.5
    def lam(w):
        t2 = (w[:, 0] ** 2 + w[:, 1] ** 2) / w[:, 2] ** 2
        return (np.sqrt(1 + a * a * t2) - 1) / 2
    D = 1 / (np.pi * a * a * h[:, 2] ** 4 * (1 + (h[:, 0] ** 2 + h[:, 1] ** 2) / (a * a * h[:, 2] ** 2)) ** 2)
    G = 1 / (1 + lam(wo) + lam(wi))
    wih, woh = np.sum(wi * h, 1), np.sum(wo * h, 1)
    ok = (wih * wi[:, 2] >= 0) & (woh * wo[:, 2] >= 0)
    ref = D * G * (1 - F) * np.abs(wih * woh / (wo[:, 2] * wi[:, 2] * (wih + woh / etap) ** 2)) / etap ** 2
    ref = np.where(ok, ref, 0.0)
    sel = ok & (ref > 1e-3 * ref.max())
    np.testing.assert_allclose(f[sel], ref[sel], rtol=1e-9)
