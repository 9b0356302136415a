"""Measured materials: writers and tabulation (``bk.measured``).

* :func:`write_merl` tabulates any isotropic bsdfkit model on MERL's grid and writes a
  ``.binary`` file that :class:`bsdfkit.MERL` (and MERL's own reader) loads.
* :func:`merl_directions` gives the (wo, wi) pair at the centre of every MERL bin.
* :func:`tabulate` builds the Dupuy & Jakob (2018) representation of any model (an in-memory
  :class:`bsdfkit.Measured`; ``.save(path)`` writes a tensor file Mitsuba's ``measured`` loads).
* :func:`read_tensor` / :func:`write_tensor`: the RGL tensor container.

The model classes live in :mod:`bsdfkit.models.measured` (``bk.MERL``, ``bk.Measured``).
"""
from __future__ import annotations

import os

import numpy as np

from .models.measured import (_F32_MAX, MERL, MERL_DIMS, MERL_SCALE, Measured, read_merl, read_tensor,
                              tensor_bytes, write_tensor)

__all__ = ["write_merl", "merl_directions", "read_merl", "check_isotropic", "tabulate", "projected_area",
           "read_tensor", "write_tensor", "tensor_bytes", "MERL", "Measured"]


def merl_directions() -> tuple[np.ndarray, np.ndarray]:
    """(wo, wi), each float64 (90, 90, 180, 3): the directions at the centre of every MERL bin
    (theta_h = (pi/2) ((i + 1/2) / 90)^2, theta_d = (j + 1/2) (pi/2) / 90, phi_d = (k + 1/2) pi / 180,
    phi_h = 0). wi is MERL's "in" (light) direction, from which the difference angles are taken;
    wo is its mirror image about the half vector."""
    nh, nd, npd = MERL_DIMS
    th = 0.5 * np.pi * ((np.arange(nh) + 0.5) / nh) ** 2
    td = (np.arange(nd) + 0.5) * (0.5 * np.pi / nd)
    pd = (np.arange(npd) + 0.5) * (np.pi / npd)
    th, td, pd = np.meshgrid(th, td, pd, indexing="ij")
    dx, dy, dz = np.sin(td) * np.cos(pd), np.sin(td) * np.sin(pd), np.cos(td)
    ct, st = np.cos(th), np.sin(th)
    # undo the rotation by -theta_h about the binormal (phi_h = 0)
    wi = np.stack([ct * dx + st * dz, dy, -st * dx + ct * dz], axis=-1)
    h = np.stack([st, np.zeros_like(st), ct], axis=-1)
    wo = 2 * np.sum(wi * h, axis=-1, keepdims=True) * h - wi
    wo /= np.linalg.norm(wo, axis=-1, keepdims=True)
    wi /= np.linalg.norm(wi, axis=-1, keepdims=True)
    return wo, wi


def check_isotropic(model, *, n=2048, rtol=1e-5, seed=0) -> None:
    """Raise ValueError if ``model`` is not isotropic: f(R wo, R wi) must equal f(wo, wi) for
    rotations R about the normal (checked on ``n`` random pairs, relative tolerance ``rtol``)."""
    rng = np.random.default_rng(seed)
    wo = rng.normal(size=(n, 3))
    wi = rng.normal(size=(n, 3))
    wo[:, 2], wi[:, 2] = np.abs(wo[:, 2]) + 0.05, np.abs(wi[:, 2]) + 0.05
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    phi = rng.uniform(0, 2 * np.pi, n)
    c, s = np.cos(phi), np.sin(phi)

    def rot(w):
        return np.stack([c * w[:, 0] - s * w[:, 1], s * w[:, 0] + c * w[:, 1], w[:, 2]], axis=1)

    f0, f1 = model.eval(wo, wi), model.eval(rot(wo), rot(wi))
    scale = np.maximum(np.abs(f0), np.abs(f1))
    err = np.abs(f0 - f1) / np.where(scale > 0, scale, 1.0)
    # ignore pairs where the value is tiny compared with the model's typical value
    err = np.where(scale > 1e-6 * max(float(np.median(scale)), 1e-12), err, 0.0)
    if float(err.max()) > rtol:
        raise ValueError(f"model: {model!r} is not isotropic (f changes by {float(err.max()):.3g} relative under a "
                         "rotation about the normal); MERL tables hold isotropic BRDFs only")


def write_merl(path, model, *, check: bool = True) -> str:
    """Tabulate an isotropic bsdfkit model on MERL's 90 x 90 x 180 grid and write a MERL
    ``.binary`` file (3 int32 dims, then float64 red, green, blue planes, little-endian, each
    value f / scale at the bin centre, see :func:`merl_directions`). Bins where either direction
    is below the horizon are written as -1 ("not measured"). ``check`` tests isotropy first
    (:func:`check_isotropic`). Raises ValueError for values :func:`read_merl` would refuse
    (non-finite, or beyond float32's max once divided by the scales). Returns the absolute path."""
    if not hasattr(model, "eval"):
        raise TypeError(f"model: expected a bsdfkit model, got {type(model).__name__}")
    if check:
        check_isotropic(model)
    wo, wi = merl_directions()
    ok = (wo[..., 2] > 0) & (wi[..., 2] > 0)
    f = model.eval(wo, wi)
    raw = f / np.asarray(MERL_SCALE)
    raw = np.where(ok[..., None], raw, -1.0)
    if not np.all(np.isfinite(raw)):
        raise ValueError(f"model: {model!r} gave non-finite values on the MERL grid")
    if np.any(raw > _F32_MAX):
        raise ValueError(f"model: {model!r} gave values up to {float(raw.max()):.9g} on the MERL grid (after MERL's "
                         f"channel scales), beyond float32's max {_F32_MAX:.9g}: read_merl refuses them")
    ap = os.path.abspath(os.fspath(path))
    with open(ap, "wb") as fh:
        fh.write(np.asarray(MERL_DIMS, "<i4").tobytes())
        fh.write(np.ascontiguousarray(np.moveaxis(raw, -1, 0), "<f8").tobytes())
    return ap


# ================================================================ tabulation (Dupuy & Jakob 2018)

_LUM = np.array([0.2126, 0.7152, 0.0722])   # Rec. 709 luminance of linear sRGB


def _u2theta(u):
    return u * u * (np.pi / 2)


def _u2phi(u):
    return (2 * u - 1) * np.pi


def _theta2u(t):
    return np.sqrt(np.maximum(t, 0) * (2 / np.pi))


def _phi2u(p):
    return (p + np.pi) / (2 * np.pi)


def _sph(theta, phi):
    st = np.sin(theta)
    return np.stack(np.broadcast_arrays(st * np.cos(phi), st * np.sin(phi), np.cos(theta)), axis=-1)


def _bilinear(table, pts):
    """Bilinear interpolation of an (H, W) table over [0,1]^2 at pts (..., 2) = (x, y) (as the warps)."""
    H, W = table.shape
    x = np.clip(pts[..., 0], 0, 1) * (W - 1)
    y = np.clip(pts[..., 1], 0, 1) * (H - 1)
    ix = np.minimum(x.astype(np.int64), W - 2)
    iy = np.minimum(y.astype(np.int64), H - 2)
    fx, fy = x - ix, y - iy
    v00, v10 = table[iy, ix], table[iy, ix + 1]
    v01, v11 = table[iy + 1, ix], table[iy + 1, ix + 1]
    return (1 - fy) * ((1 - fx) * v00 + fx * v10) + fy * ((1 - fx) * v01 + fx * v11)


def ndf_quadrature(n: int = 96):
    """Midpoint quadrature over the hemisphere in the (u_theta, u_phi) square: points (n*n, 2) in
    [0,1]^2, their directions (n*n, 3) and solid-angle weights (dw = 2 pi^2 u sin(theta) du dv)."""
    u = (np.arange(n) + 0.5) / n
    ux, uy = np.meshgrid(u, u, indexing="xy")
    pts = np.stack([ux.ravel(), uy.ravel()], axis=-1)
    th = _u2theta(pts[:, 0])
    w = 2 * np.pi ** 2 * pts[:, 0] * np.sin(th) / (n * n)
    return pts, _sph(th, _u2phi(pts[:, 1])), w


def projected_area(ndf: np.ndarray, dirs: np.ndarray, n: int = 96) -> np.ndarray:
    """sigma(w) = integral of D(m) max(0, w . m) dm for the NDF table ``ndf`` (bilinear over the
    unit square, as the file is evaluated), at directions (..., 3)."""
    pts, m, w = ndf_quadrature(n)
    return _clamped_cos_apply(dirs.reshape(-1, 3), m, _bilinear(ndf, pts) * w)


#: Rows of the (rows, quadrature points) clamped-cosine kernel formed per step. Each step is a
#: fraction of a second, and Ctrl-C (KeyboardInterrupt) lands between steps -- one matrix of all
#: rows at once ran for 10-20 s at resolution 128 without a chance to stop.
_KERNEL_ROWS = 256
#: The kernel is kept between power iterations (tabulate's step 1) up to this many bytes.
_KERNEL_CACHE_BYTES = 512 << 20


def _clamped_cos_apply(w_rows: np.ndarray, m_q: np.ndarray, d: np.ndarray, cache: list | None = None) -> np.ndarray:
    """``max(0, w_rows @ m_q.T) @ d`` in row blocks of _KERNEL_ROWS. ``cache``: a list that keeps
    the blocks for the next call with the same ``w_rows`` and ``m_q`` while they fit in
    _KERNEL_CACHE_BYTES (blocks beyond it are recomputed each call)."""
    out = np.empty(len(w_rows))
    limit = _KERNEL_CACHE_BYTES // max(1, len(m_q) * 8 * _KERNEL_ROWS)
    for k, i in enumerate(range(0, len(w_rows), _KERNEL_ROWS)):
        if cache is not None and k < len(cache):
            kern = cache[k]
        else:
            kern = np.maximum(w_rows[i:i + _KERNEL_ROWS] @ m_q.T, 0)
            if cache is not None and k < limit:
                cache.append(kern)
        out[i:i + len(kern)] = kern @ d
    return out


def tabulate(model, resolution: int = 32, *, n_theta: int | None = None, n_phi: int | None = None,
             isotropic: bool | None = None, reduction: int = 1, iterations: int = 8,
             description: str | None = None):
    """The Dupuy & Jakob (2018) representation of any bsdfkit model, as an in-memory
    :class:`bsdfkit.Measured` (``.save(path)`` writes an RGB tensor file that Mitsuba's
    ``measured`` plugin loads).

    resolution: side N of every 2-D table (ndf, sigma, vndf, luminance, rgb are N x N).
    n_theta: incidence elevations theta_i (default max(6, N / 4)), u-spaced (theta = u^2 pi/2)
    from 0 to 88 degrees. n_phi: incidence azimuths for anisotropic models (default 2 n_theta + 1,
    spanning [-pi, pi]). isotropic: None detects it (:func:`check_isotropic`). reduction: 1, or
    2 / 4 for an anisotropic model symmetric under y -> -y (and x -> -x): the incidence azimuths
    then span [-pi, 0] or [-pi, -pi/2] and readers fold wo into that range (Mitsuba's reductions).

    Construction (the paper's pipeline with the model in place of the goniophotometer):
    1. NDF from retro-reflection: with f(w, w) = F D(w) G1(w) / (4 cos^2) and G1 = cos / sigma,
       D(w) is proportional to lum f(w, w) cos(theta) sigma(w); solved by ``iterations`` power
       iterations (Dupuy et al. 2015), normalised so that integral D cos(theta_m) dm = 1
       (isotropic: averaged over azimuth).
    2. sigma(w) = integral D(m) max(0, w . m) dm on the table's nodes (quadrature of the
       bilinear NDF, :func:`projected_area`).
    3. VNDF per incidence: D(m) max(0, wo . m) as a density over the u square (times the
       Jacobian 2 pi^2 u sin(theta_m)).
    4. rgb per incidence, on the N x N sample-space grid mapped through the VNDF warp to wm:
       f(wo, wi) cos(theta_i) 4 sigma(wo) / D(wm) (``jacobian`` = 1), wi = reflect(wo, wm);
       luminance = its Rec. 709 luminance (floored at 1e-3 of the slice mean, so the sampler
       covers every direction the model reflects into).
    """
    from ._core import Warp2D
    from .models.measured import Measured, tensor_bytes
    N = int(resolution)
    if not 4 <= N <= 512:
        raise ValueError(f"resolution: must be an integer in [4, 512], got {resolution!r}")
    nth = max(6, N // 4) if n_theta is None else int(n_theta)
    if not 2 <= nth <= 256:
        raise ValueError(f"n_theta: must be in [2, 256], got {n_theta!r}")
    if isotropic is None:
        try:
            check_isotropic(model)
            isotropic = True
        except ValueError:
            isotropic = False
    nph = 1 if isotropic else (2 * nth + 1 if n_phi is None else int(n_phi))
    if not isotropic and not 3 <= nph <= 512:
        raise ValueError(f"n_phi: must be in [3, 512] for an anisotropic table, got {n_phi!r}")
    if reduction not in (1, 2, 4):
        raise ValueError(f"reduction: must be 1, 2 or 4, got {reduction!r}")
    if isotropic and reduction != 1:
        raise ValueError("reduction: only anisotropic tables are reduced")
    node = np.arange(N) / (N - 1)
    # ---- 1. NDF from retro-reflection (power iteration)
    ux, uy = np.meshgrid(node, node, indexing="xy")            # (N rows = u_phi, N cols = u_theta)
    th = np.minimum(_u2theta(ux), np.pi / 2 - 1e-3)
    w_nodes = _sph(th, _u2phi(uy))
    retro = np.maximum(model.eval(w_nodes, w_nodes) @ _LUM, 0) * w_nodes[..., 2]
    if isotropic:
        retro = np.broadcast_to(retro.mean(axis=0, keepdims=True), retro.shape).copy()
    pts, m_q, w_q = ndf_quadrature(96)
    w_rows, kern = w_nodes.reshape(-1, 3), []                   # kern: blocks of max(0, w . m), (N*N, Q)
    ndf = np.ones((N, N))
    for _ in range(max(1, int(iterations))):
        sigma = _clamped_cos_apply(w_rows, m_q, _bilinear(ndf, pts) * w_q, kern)
        ndf = retro * sigma.reshape(N, N)
        norm = float(np.sum(_bilinear(ndf, pts) * m_q[:, 2] * w_q))
        if not norm > 0:
            raise ValueError(f"model: {model!r} reflects nothing back towards the light; no NDF can be recovered")
        ndf /= norm
    # ---- 2. projected area on the nodes (exact directions, horizon included)
    w_exact = _sph(_u2theta(ux), _u2phi(uy))
    sigma = _clamped_cos_apply(w_exact.reshape(-1, 3), m_q, _bilinear(ndf, pts) * w_q).reshape(N, N)
    # ---- incidence grid
    theta_i = _u2theta(np.linspace(0, _theta2u(np.radians(88.0)), nth))
    phi_i = np.array([0.0]) if isotropic else np.linspace(-np.pi, -np.pi + 2 * np.pi / reduction, nph)
    vndf = np.zeros((nph, nth, N, N))
    rgb = np.zeros((nph, nth, 3, N, N))
    lum = np.zeros((nph, nth, N, N))
    s_nodes = np.stack([ux.ravel(), uy.ravel()], axis=-1)     # sample-space nodes (x, y)
    for p, ph_i in enumerate(phi_i):
        for t, th_i in enumerate(theta_i):
            wo = _sph(th_i, ph_i)
            # ---- 3. VNDF over the u square (row = u_phi of wm, relative for isotropic tables)
            phm = _u2phi(uy) + (ph_i if isotropic else 0.0)
            thm = _u2theta(ux)
            m = _sph(thm, phm)
            vndf[p, t] = ndf * np.maximum(m @ wo, 0) * 2 * np.pi ** 2 * ux * np.sin(thm)
            # ---- 4. reflectance on the sample-space grid through this slice's warp
            um, _ = Warp2D(vndf[p, t], True).sample(s_nodes, False)
            m = _sph(_u2theta(um[:, 0]), _u2phi(um[:, 1]) + (ph_i if isotropic else 0.0))
            wi = 2 * (m @ wo)[:, None] * m - wo
            wi /= np.linalg.norm(wi, axis=1, keepdims=True)
            ok = wi[:, 2] > 0
            f = model.eval(wo, np.where(ok[:, None], wi, [0.0, 0.0, 1.0]))
            d_m = _bilinear(ndf, um)
            s_o = _bilinear(sigma, np.array([_theta2u(th_i), _phi2u(ph_i)]))
            val = f * (wi[:, 2] * 4 * s_o / np.where(d_m > 0, d_m, 1.0))[:, None]
            val = np.where((ok & (d_m > 0))[:, None], val, 0.0)
            rgb[p, t] = val.T.reshape(3, N, N)
            l = np.maximum(val @ _LUM, 0).reshape(N, N)
            lum[p, t] = l + 1e-3 * max(float(l.mean()), 1e-12)
    desc = description if description is not None else f"bsdfkit.measured.tabulate({model!r}, resolution={N})"
    fields = {
        "description": np.frombuffer(desc.encode("utf-8"), np.uint8),
        "jacobian": np.array([1], np.uint8),
        "theta_i": theta_i.astype(np.float32),
        "phi_i": phi_i.astype(np.float32),
        "ndf": ndf.astype(np.float32),
        "sigma": sigma.astype(np.float32),
        "vndf": vndf.astype(np.float32),
        "luminance": lum.astype(np.float32),
        "rgb": rgb.astype(np.float32),
    }
    return Measured.from_bytes(tensor_bytes(fields))
