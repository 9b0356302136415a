"""Independent float64 reference for the layered models: an explicit photon simulation of the
slab (numpy), written from the physics, not from bsdfkit's C++ or pbrt-v4's estimator.

Geometry: the coating interface at z = thickness (outside above, relative IOR ``eta`` below),
a homogeneous medium with extinction 1 (thickness in mean free paths), single-scattering
``albedo`` and Henyey-Greenstein phase function (asymmetry ``g``, propagation convention:
g > 0 scatters forward), and the base at z = 0 (Lambertian, or a microfacet conductor whose
complex IOR is given relative to the coating). Photons arrive along -wo and are followed event
by event until they leave through the top or are absorbed:

* interfaces (smooth or GGX-rough dielectric, and the conductor): the single-scattering
  microfacet model of Walter et al. 2007 simulated as a random event: a microfacet normal m is
  drawn from the distribution of visible normals of the incident direction (Heitz 2018), the
  photon reflects with probability F(wo.m) (exact Fresnel, total internal reflection included)
  or refracts by Snell's law through m, and it keeps the fraction G2(wo, wi) / G1(wo) of its
  weight (Smith masking of the outgoing direction: height-correlated or separable); for a
  conductor the weight is also multiplied by F. This is the microfacet BSDF's own sampling
  weight, so the simulated interface is exactly the microfacet BSDF.
* medium: exponential free flights; at a scattering event the weight is multiplied by the
  albedo and the direction is drawn from HG by inversion.
* Russian roulette below a weight of 0.1 (unbiased).

The exit directions are binned in (cos theta, phi); each bin's mean weight per photon estimates
the integral over the bin of f(wo, wi) cos(theta_i) (photon weights are flux; the slab's BRDF is
reciprocal, so the radiance-mode f of a model gives the same integral). Photons that reflect
specularly at the entrance of a smooth coating are reported separately (a delta lobe that
``eval`` does not contain).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._enums import BxDFFlags

__all__ = ["Slab", "simulate", "bin_solid_angles", "bin_edges", "bins_eval", "bins_sample", "z_scores", "assert_z"]


@dataclass(frozen=True)
class Slab:
    eta: float = 1.5                 # coating IOR relative to outside
    alpha: float = 0.0               # GGX alpha of the coating (isotropic; < 1e-3 smooth)
    thickness: float = 0.01          # mean free paths
    albedo: tuple = (0.0, 0.0, 0.0)
    g: float = 0.0
    base: str = "diffuse"            # "diffuse" or "conductor"
    reflectance: tuple = (0.5, 0.5, 0.5)   # diffuse base
    cond_eta: tuple = (1.0, 1.0, 1.0)      # conductor IOR relative to the coating
    cond_k: tuple = (0.0, 0.0, 0.0)
    cond_alpha: float = 0.0
    masking: str = "correlated"


def bin_edges(n_cos, n_phi):
    return np.linspace(0.0, 1.0, n_cos + 1), np.linspace(0.0, 2 * np.pi, n_phi + 1)


def bin_solid_angles(n_cos, n_phi):
    return np.full((n_cos, n_phi), (1.0 / n_cos) * (2 * np.pi / n_phi))


# ------------------------------------------------------------------ microfacet pieces (GGX)

def _lambda(alpha, w):
    t2 = (w[:, 0] ** 2 + w[:, 1] ** 2) / np.maximum(w[:, 2] ** 2, 1e-300)
    return 0.5 * (np.sqrt(1 + alpha * alpha * t2) - 1)


def _vndf(alpha, wo, u1, u2):
    """Heitz 2018, "Sampling the GGX distribution of visible normals" (wo.z > 0)."""
    vh = np.stack([alpha * wo[:, 0], alpha * wo[:, 1], wo[:, 2]], 1)
    vh /= np.linalg.norm(vh, axis=1, keepdims=True)
    lensq = vh[:, 0] ** 2 + vh[:, 1] ** 2
    inv = np.where(lensq > 0, 1 / np.sqrt(np.where(lensq > 0, lensq, 1)), 0.0)
    t1 = np.where((lensq > 0)[:, None], np.stack([-vh[:, 1] * inv, vh[:, 0] * inv, 0 * inv], 1), [1.0, 0.0, 0.0])
    t2 = np.cross(vh, t1)
    r, phi = np.sqrt(u1), 2 * np.pi * u2
    p1, p2 = r * np.cos(phi), r * np.sin(phi)
    s = 0.5 * (1 + vh[:, 2])
    p2 = (1 - s) * np.sqrt(np.maximum(0, 1 - p1 * p1)) + s * p2
    p3 = np.sqrt(np.maximum(0, 1 - p1 * p1 - p2 * p2))
    nh = p1[:, None] * t1 + p2[:, None] * t2 + p3[:, None] * vh
    m = np.stack([alpha * nh[:, 0], alpha * nh[:, 1], np.maximum(1e-7, nh[:, 2])], 1)
    return m / np.linalg.norm(m, axis=1, keepdims=True)


def _fresnel_dielectric(c, eta):
    """Unpolarized Fresnel reflectance for cos c > 0 on the incident side, relative IOR eta."""
    s2t = (1 - c * c) / (eta * eta)
    tir = s2t >= 1
    ct = np.sqrt(np.maximum(0, 1 - s2t))
    rs = (c - eta * ct) / (c + eta * ct)
    rp = (eta * c - ct) / (eta * c + ct)
    return np.where(tir, 1.0, 0.5 * (rs * rs + rp * rp)), ct


def _fresnel_conductor(c, eta, k):
    """Born & Wolf with complex IOR n = eta + i k (numpy complex arithmetic); c (N,), eta/k (3,)."""
    n = (np.asarray(eta) + 1j * np.asarray(k))[None, :]
    ci = c[:, None].astype(complex)
    ct = np.sqrt(1 - (1 - ci * ci) / (n * n))
    rs = (ci - n * ct) / (ci + n * ct)
    rp = (n * ci - ct) / (n * ci + ct)
    return 0.5 * (np.abs(rs) ** 2 + np.abs(rp) ** 2)


def _masking_weight(alpha, wo, wi, masking):
    """G2(wo, wi) / G1(wo) for the sampled pair (wo on the +z side)."""
    lo, li = _lambda(alpha, wo), _lambda(alpha, wi)
    if masking == "correlated":
        return (1 + lo) / (1 + lo + li)
    return 1 / (1 + li)


def _interface(d, eta_rel, alpha, rng, masking):
    """A photon with propagation direction d meets a dielectric interface whose other side has
    relative IOR eta_rel. Returns (new propagation direction, weight factor, transmitted)."""
    s = np.where(d[:, 2] < 0, 1.0, -1.0)          # flip to the incident side = +z
    wo = -d * s[:, None]
    n = len(d)
    if alpha < 1e-3:
        m = np.tile([0.0, 0.0, 1.0], (n, 1))
    else:
        m = _vndf(alpha, wo, rng.random(n), rng.random(n))
    c = np.sum(wo * m, 1)
    F, ct = _fresnel_dielectric(c, eta_rel)
    refl = rng.random(n) < F
    wr = -wo + 2 * c[:, None] * m
    wt = -wo / eta_rel + (c / eta_rel - ct)[:, None] * m
    wi = np.where(refl[:, None], wr, wt)
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    ok = np.where(refl, wi[:, 2] > 0, wi[:, 2] < 0)
    wgt = np.ones(n) if alpha < 1e-3 else _masking_weight(alpha, wo, wi, masking)
    wgt = np.where(ok, wgt, 0.0)
    # back to world: the new propagation direction is wi in the flipped frame
    return wi * s[:, None], wgt, ~refl


def _conductor(d, slab, rng):
    """Photon going down (d.z < 0) meets the conductor base: new direction, RGB weight factor."""
    wo = -d
    n = len(d)
    a = slab.cond_alpha
    m = np.tile([0.0, 0.0, 1.0], (n, 1)) if a < 1e-3 else _vndf(a, wo, rng.random(n), rng.random(n))
    c = np.clip(np.sum(wo * m, 1), 0, 1)
    wi = -wo + 2 * c[:, None] * m
    F = _fresnel_conductor(c, slab.cond_eta, slab.cond_k)
    wgt = np.ones(n) if a < 1e-3 else _masking_weight(a, wo, wi, slab.masking)
    wgt = np.where(wi[:, 2] > 0, wgt, 0.0)
    return wi, F * wgt[:, None]


def _cosine_up(rng, n):
    u1, u2 = rng.random(n), rng.random(n)
    r, phi = np.sqrt(u1), 2 * np.pi * u2
    return np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(np.maximum(0, 1 - u1))], 1)


def _hg(d, g, rng):
    """New propagation direction: HG in the angle to the old one (propagation convention)."""
    n = len(d)
    u1, u2 = rng.random(n), rng.random(n)
    if abs(g) < 1e-3:
        ct = 1 - 2 * u1
    else:
        ct = (1 + g * g - ((1 - g * g) / (1 - g + 2 * g * u1)) ** 2) / (2 * g)
    ct = np.clip(ct, -1, 1)
    st = np.sqrt(1 - ct * ct)
    phi = 2 * np.pi * u2
    # any orthonormal frame around d
    a = np.where(np.abs(d[:, 0:1]) > 0.9, [[0.0, 1.0, 0.0]], [[1.0, 0.0, 0.0]])
    t1 = np.cross(d, a)
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    t2 = np.cross(d, t1)
    return (st * np.cos(phi))[:, None] * t1 + (st * np.sin(phi))[:, None] * t2 + ct[:, None] * d


def simulate(slab: Slab, wo, n_photons, *, seed=0, n_cos=6, n_phi=8, max_events=2000, chunk=200_000):
    """Trace n_photons arriving along -wo (wo.z > 0). Returns a dict with

    * ``mean`` (n_cos, n_phi, 3): mean exit weight per photon in each (cos theta, phi) bin,
      i.e. an unbiased estimate of the integral of f(wo, wi) cos(theta_i) over the bin (the
      smooth coating's specular entrance reflection excluded);
    * ``var`` (n_cos, n_phi, 3): variance of that mean;
    * ``specular`` (3,): weight of the specular entrance reflection per photon (smooth coats);
    * ``albedo`` (3,): total exit weight per photon (everything, specular included);
    * ``truncated``: fraction of photons still alive after max_events (should be ~0).

    Channels: 3, or more when the slab's channel parameters (albedo, and reflectance or
    cond_eta / cond_k) have more entries (e.g. 4 wavelengths; give them all the same length).
    """
    rng = np.random.default_rng(seed)
    wo = np.asarray(wo, float) / np.linalg.norm(wo)
    base = slab.reflectance if slab.base == "diffuse" else slab.cond_eta
    nc = max(3, np.size(slab.albedo), np.size(base))
    alb = np.broadcast_to(np.asarray(slab.albedo, float), (nc,))
    R = np.broadcast_to(np.asarray(slab.reflectance, float), (nc,)) if slab.base == "diffuse" else None
    ce, cos_edges, phi_edges = None, *bin_edges(n_cos, n_phi)
    s1 = np.zeros((n_cos, n_phi, nc))
    s2 = np.zeros((n_cos, n_phi, nc))
    spec = np.zeros(nc)
    total = np.zeros(nc)
    alive_end = 0
    done = 0
    while done < n_photons:
        n = min(chunk, n_photons - done)
        done += n
        d = np.tile(-wo, (n, 1))
        # entrance
        d, wgt, tr = _interface(d, slab.eta, slab.alpha, rng, slab.masking)
        w = wgt[:, None] * np.ones((1, nc))
        # photons that reflect at the entrance leave at once
        out = ~tr
        _tally(d[out], w[out], s1, s2, cos_edges, phi_edges, specular=slab.alpha < 1e-3, spec_acc=spec)
        total += w[out].sum(0)
        idx = np.flatnonzero(tr & (wgt > 0))
        d, w = d[idx], w[idx]
        z = np.full(len(idx), slab.thickness)
        for _ in range(max_events):
            if len(d) == 0:
                break
            # free flight
            s = -np.log(1 - rng.random(len(d)))
            zp = z + s * d[:, 2]
            inside = (zp > 0) & (zp < slab.thickness)
            # scattering in the medium (albedo 0 absorbs)
            # which boundary each non-scattering photon reaches (before any direction changes)
            sc = np.flatnonzero(inside)
            bo = np.flatnonzero(~inside & (d[:, 2] < 0))
            tp = np.flatnonzero(~inside & (d[:, 2] > 0))
            w[sc] *= alb
            d[sc] = _hg(d[sc], slab.g, rng)
            z[sc] = zp[sc]
            # the base
            z[bo] = 0.0
            if slab.base == "diffuse":
                d[bo] = _cosine_up(rng, len(bo))
                w[bo] *= R
            else:
                d[bo], fw = _conductor(d[bo], slab, rng)
                w[bo] *= fw
            # the coating from inside
            z[tp] = slab.thickness
            nd, wg, tr = _interface(d[tp], 1.0 / slab.eta, slab.alpha, rng, slab.masking)
            d[tp] = nd
            w[tp] *= wg[:, None]
            leave = np.zeros(len(d), bool)
            leave[tp[tr]] = True
            _tally(d[leave], w[leave], s1, s2, cos_edges, phi_edges)
            total += w[leave].sum(0)
            keep = ~leave & (w.max(1) > 0)
            # Russian roulette on small weights
            low = keep & (w.max(1) < 0.1)
            surv = rng.random(len(d)) < 0.5
            w[low & surv] *= 2
            keep &= ~(low & ~surv)
            d, w, z = d[keep], w[keep], z[keep]
        alive_end += len(d)
    mean = s1 / n_photons
    var = (s2 / n_photons - mean ** 2) / n_photons
    return {"mean": mean, "var": var, "specular": spec / n_photons, "albedo": total / n_photons,
            "truncated": alive_end / n_photons}


def _tally(d, w, s1, s2, cos_edges, phi_edges, specular=False, spec_acc=None):
    if len(d) == 0:
        return
    if specular:
        spec_acc += w.sum(0)
        return
    ci = np.clip(np.searchsorted(cos_edges, d[:, 2], side="right") - 1, 0, len(cos_edges) - 2)
    ph = np.mod(np.arctan2(d[:, 1], d[:, 0]), 2 * np.pi)
    pi = np.clip(np.searchsorted(phi_edges, ph, side="right") - 1, 0, len(phi_edges) - 2)
    for c in range(s1.shape[-1]):
        np.add.at(s1[..., c], (ci, pi), w[:, c])
        np.add.at(s2[..., c], (ci, pi), w[:, c] ** 2)


# ------------------------------------------------------------------ a model's estimates per bin

def bins_eval(model, wo, K, rng, n_cos=6, n_phi=8, **kw):
    """Monte Carlo estimate of the integral of E[f] cos over each (cos theta, phi) bin from K
    uniform directions per bin (each an independent realization of a stochastic f): (mean,
    variance of the mean), (n_cos, n_phi, channels). ``kw`` goes to ``model.eval`` (e.g.
    ``wavelengths``)."""
    ce, pe = bin_edges(n_cos, n_phi)
    c = ce[:-1, None, None] + (ce[1] - ce[0]) * rng.random((n_cos, n_phi, K))
    p = pe[None, :-1, None] + (pe[1] - pe[0]) * rng.random((n_cos, n_phi, K))
    s = np.sqrt(1 - c * c)
    wi = np.stack([s * np.cos(p), s * np.sin(p), c], -1)
    fc = model.eval(np.broadcast_to(wo, wi.shape), wi, **kw) * c[..., None]
    om = bin_solid_angles(n_cos, n_phi)[..., None]
    return om * fc.mean(2), om ** 2 * fc.var(2, ddof=1) / K


def bins_sample(model, wo, n, seed, n_cos=6, n_phi=8, **kw):
    """The weighted histogram of n samples' f |cos| / pdf over the bins (specular samples and
    samples below the surface left out): (mean, variance of the mean) per bin and channel. ``kw``
    goes to ``model.sample``."""
    s = model.sample(wo, n=n, seed=seed, **kw)
    w = s.weight
    spec = (s.flags & BxDFFlags.Specular) != 0
    keep = s.valid & ~spec & (s.wi[:, 2] > 0)
    ce, pe = bin_edges(n_cos, n_phi)
    ci = np.clip(np.searchsorted(ce, s.wi[:, 2], side="right") - 1, 0, n_cos - 1)
    ph = np.mod(np.arctan2(s.wi[:, 1], s.wi[:, 0]), 2 * np.pi)
    pj = np.clip(np.searchsorted(pe, ph, side="right") - 1, 0, n_phi - 1)
    nc = w.shape[-1]
    s1 = np.zeros((n_cos, n_phi, nc))
    s2 = np.zeros((n_cos, n_phi, nc))
    for c in range(nc):
        np.add.at(s1[..., c], (ci[keep], pj[keep]), w[keep, c])
        np.add.at(s2[..., c], (ci[keep], pj[keep]), w[keep, c] ** 2)
    m = s1 / n
    return m, (s2 / n - m * m) / n


def z_scores(m, v, ref):
    """Per bin and channel z of an estimate (mean m, variance v) against a simulate() result."""
    return (m - ref["mean"]) / np.sqrt(v + ref["var"] + 1e-300)


def assert_z(z, what):
    """Every |z| < 4.5 (1e-3 family-wise over ~150 bin x channel cells, Bonferroni) and the
    root-mean-square z < 1.5 (a systematic offset shows there first)."""
    rms = np.sqrt(np.mean(z ** 2))
    print(f"{what}: max |z| {np.abs(z).max():.2f}, rms z {rms:.2f}, mean z {z.mean():.2f}")
    assert np.abs(z).max() < 4.5 and rms < 1.5, what
