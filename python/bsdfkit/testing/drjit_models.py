"""Float64 reference formulas of pbrt-v4's reflection models, written with Dr.Jit.

Independent of both the bsdfkit C++ core and Mitsuba: each function restates one pbrt-v4 formula
(pbrt-v4 ``util/scattering.h`` and ``bxdfs.{h,cpp}``; notation of
``/work/shared/research/pbrt_filament.md`` §1.2-1.7) in double precision on Dr.Jit's LLVM backend
(``drjit.llvm.Float64``; ``drjit.scalar.ArrayXf64`` if there is no LLVM backend).

Conventions: directions are ``(..., 3)`` numpy arrays in the local shading frame (z = normal),
both pointing away from the surface; ``wo`` is toward the camera, ``wi`` the other direction;
``f`` excludes the cosine. All inputs broadcast with numpy rules and all outputs are float64
numpy arrays of the broadcast batch shape (plus a trailing 3 for spectra). Directions are used
as given (pbrt's trigonometric helpers assume unit vectors; ``Sin2Theta = max(0, 1 - z^2)``).

The microfacet functions (``tr_*``) are the raw distribution formulas and need alpha > 0; the
model functions apply pbrt's constructor rules (smooth if ``max(alpha) < 1e-3`` -> delta lobes,
``f = pdf = 0``; otherwise each alpha is raised to >= 1e-4).

Implementation note: ``dr.maximum``/``dr.minimum``/``dr.clip``/``dr.safe_sqrt`` are avoided on
purpose (they emit ``llvm.maximum``, which LLVM 15/16 cannot compile on x86); selects are used.
"""

import numpy as np

from . import _drjit_backend

__all__ = [
    "tr_D", "tr_lambda", "tr_G1", "tr_G_correlated", "tr_G_separable", "tr_vndf_pdf",
    "fr_dielectric", "fr_complex", "fr_schlick_conductor", "fr_f82_conductor", "conductor_fresnel",
    "conductor_f", "conductor_pdf", "dielectric_f_pdf",
    "diffuse_f_pdf", "diffuse_transmission_f_pdf", "thin_dielectric_R",
]

SMOOTH_ALPHA = 1e-3  # pbrt-v4 TrowbridgeReitzDistribution::EffectivelySmooth
MIN_ALPHA = 1e-4     # pbrt-v4 TrowbridgeReitzDistribution constructor floor
INV_PI = 1.0 / np.pi

#: Forward-mode AD tracer (bsdfkit.testing.drjit_grad): when set, arrays are drjit.llvm.ad
#: Float64, ``_prep`` lets it enable gradients on the parameters and ``_out``/``_out3`` let it
#: propagate them. None: plain evaluation.
_TRACE = None


def _bk():
    """(dr, Float64 array type) of the shared backend (references._drjit_backend)."""
    dr, B = _drjit_backend()
    if _TRACE is not None:
        return dr, _TRACE.Float64
    return dr, (B.Float64 if dr.has_backend(dr.JitBackend.LLVM) else B.ArrayXf64)


# ---------------------------------------------------------------------------------------------
# numpy <-> Dr.Jit plumbing
# ---------------------------------------------------------------------------------------------

class _Empty(Exception):
    """Raised by _prep for an empty batch; caught by @_outputs."""

    def __init__(self, batch):
        super().__init__(batch)
        self.batch = batch


def _outputs(*trailing):
    """Decorator: return zeros of shapes ``batch + t`` for each ``t`` in ``trailing`` when the
    broadcast batch is empty (Dr.Jit arrays cannot have width 0)."""
    import functools

    def deco(fn):
        @functools.wraps(fn)
        def wrapper(*args, **kwargs):
            try:
                return fn(*args, **kwargs)
            except _Empty as e:
                res = [np.zeros(e.batch + t) for t in trailing]
                return res[0] if len(res) == 1 else tuple(res)
        return wrapper
    return deco


def _prep(scalars=(), vectors=(), spectra=()):
    """Broadcast numpy inputs; return (batch shape, n, [Float], [(x,y,z)], [(c0,c1,c2)])."""
    s = [np.asarray(a, dtype=np.float64) for a in scalars]
    v = [np.asarray(a, dtype=np.float64) for a in vectors]
    c = [np.asarray(a, dtype=np.float64) for a in spectra]
    c = [np.full(3, float(a)) if a.ndim == 0 else a for a in c]  # grey scalar -> RGB
    for a in v:
        if a.ndim == 0 or a.shape[-1] != 3:
            raise ValueError(f"direction arrays must have shape (..., 3), got {a.shape}")
    for a in c:
        if a.ndim == 0 or a.shape[-1] != 3:
            raise ValueError(f"spectra must have shape (..., 3), got {a.shape}")
    batch = np.broadcast_shapes(*(a.shape for a in s), *(a.shape[:-1] for a in v),
                                *(a.shape[:-1] for a in c))
    n = int(np.prod(batch, dtype=np.int64))
    if n == 0:
        raise _Empty(batch)
    dr, F = _bk()

    def conv(a):
        return F(np.ascontiguousarray(np.broadcast_to(a, batch).reshape(-1)))

    fs = [conv(a) for a in s]
    vs = [tuple(conv(a[..., i]) for i in range(3)) for a in v]
    cs = [tuple(conv(a[..., i]) for i in range(3)) for a in c]
    if _TRACE is not None:
        _TRACE.prep(fs, cs)
    return batch, n, fs, vs, cs


def _direction_planes(wo, wi):
    """(batch, wo planes, wi planes): two (..., 3) direction arrays broadcast together and split
    into Dr.Jit float64 component arrays (raises _Empty for an empty batch)."""
    dr, F = _bk()
    wo, wi = np.broadcast_arrays(np.asarray(wo, np.float64), np.asarray(wi, np.float64))
    batch = wo.shape[:-1]
    if wo.size == 0:
        raise _Empty(batch)
    return (batch, tuple(F(np.ascontiguousarray(wo[..., k]).reshape(-1)) for k in range(3)),
            tuple(F(np.ascontiguousarray(wi[..., k]).reshape(-1)) for k in range(3)))


def _out(batch, *arrs):
    """Evaluate Dr.Jit arrays in one kernel and return float64 numpy arrays of shape batch."""
    dr, _ = _bk()
    if _TRACE is not None:
        _TRACE.out(batch, arrs, False)
    dr.eval(*arrs)
    res = [np.asarray(a.numpy(), dtype=np.float64).reshape(batch) for a in arrs]
    return res[0] if len(res) == 1 else res


def _out3(batch, c):
    dr, _ = _bk()
    if _TRACE is not None:
        _TRACE.out(batch, c, True)
    dr.eval(*c)
    return np.stack([np.asarray(x.numpy(), dtype=np.float64).reshape(batch) for x in c], axis=-1)


def _is_radiance(mode) -> bool:
    if isinstance(mode, (int, np.integer)) and not isinstance(mode, bool):
        return int(mode) == 0
    name = (getattr(mode, "name", None) or str(mode)).rsplit(".", 1)[-1].lower()
    if name not in ("radiance", "importance"):
        raise ValueError(f"unknown transport mode {mode!r}")
    return name == "radiance"


def _masking(m) -> str:
    m = str(m).lower()
    if m not in ("correlated", "separable"):
        raise ValueError(f"masking must be 'correlated' or 'separable', got {m!r}")
    return m


# ---------------------------------------------------------------------------------------------
# Small Dr.Jit helpers (select-based, no llvm.maximum)
# ---------------------------------------------------------------------------------------------

def _sel(m, a, b):
    return _bk()[0].select(m, a, b)


def _pos(x):
    return _sel(x > 0, x, 0.0)  # max(0, x); NaN -> 0


def _clamp(x, lo, hi):
    return _sel(x < lo, lo, _sel(x > hi, hi, x))


def _safe_sqrt(x):
    return _bk()[0].sqrt(_pos(x))


def _abs(x):
    return _bk()[0].abs(x)


def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _scale(a, s):
    return (a[0] * s, a[1] * s, a[2] * s)


def _add(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def _max_alpha_rules(ax, ay):
    """pbrt TrowbridgeReitzDistribution ctor: smooth mask and alphas floored at 1e-4."""
    smooth = _sel(ax > ay, ax, ay) < SMOOTH_ALPHA
    return smooth, _sel(ax < MIN_ALPHA, MIN_ALPHA, ax), _sel(ay < MIN_ALPHA, MIN_ALPHA, ay)


# Spherical helpers (pbrt util/vecmath.h): Cos2Theta = z^2, Sin2Theta = max(0, 1 - z^2),
# Tan2Theta = Sin2Theta / Cos2Theta (inf at z == 0), CosPhi/SinPhi = x|y / sinTheta clamped,
# (1, 0) when sinTheta == 0.
def _tan2(w):
    c2 = w[2] * w[2]
    return _pos(1.0 - c2) / c2


def _cos_sin_phi(w):
    st = _safe_sqrt(1.0 - w[2] * w[2])
    zero = st == 0
    inv = 1.0 / _sel(zero, 1.0, st)
    return (_sel(zero, 1.0, _clamp(w[0] * inv, -1.0, 1.0)),
            _sel(zero, 0.0, _clamp(w[1] * inv, -1.0, 1.0)))


# ---------------------------------------------------------------------------------------------
# Trowbridge-Reitz (GGX), anisotropic
# ---------------------------------------------------------------------------------------------

def _D(ax, ay, wm):
    dr, _ = _bk()
    t2 = _tan2(wm)
    c4 = (wm[2] * wm[2]) * (wm[2] * wm[2])
    cphi, sphi = _cos_sin_phi(wm)
    e = t2 * (cphi * cphi / (ax * ax) + sphi * sphi / (ay * ay))
    d = 1.0 / (dr.pi * ax * ay * c4 * (1.0 + e) * (1.0 + e))
    # D = 1 / (pi ax ay cos^4 (1 + tan^2 (cos^2phi/ax^2 + sin^2phi/ay^2))^2);
    # 0 if tan^2 is inf or cos^4 < 1e-16
    return _sel(dr.isinf(t2) | (c4 < 1e-16), 0.0, d)


def _lambda(ax, ay, w):
    dr, _ = _bk()
    t2 = _tan2(w)
    cphi, sphi = _cos_sin_phi(w)
    a2 = (cphi * ax) ** 2 + (sphi * ay) ** 2
    # Lambda = (sqrt(1 + alpha^2 tan^2) - 1) / 2, alpha^2 = (cosphi ax)^2 + (sinphi ay)^2;
    # 0 if tan^2 is inf
    return _sel(dr.isinf(t2), 0.0, (dr.sqrt(1.0 + a2 * t2) - 1.0) * 0.5)


def _G1(ax, ay, w):
    return 1.0 / (1.0 + _lambda(ax, ay, w))  # G1 = 1 / (1 + Lambda)


def _G(ax, ay, wo, wi, masking):
    if masking == "separable":
        return _G1(ax, ay, wo) * _G1(ax, ay, wi)  # G = G1(wo) G1(wi)
    return 1.0 / (1.0 + _lambda(ax, ay, wo) + _lambda(ax, ay, wi))  # G = 1/(1+Lo+Li)


def _vndf_pdf(ax, ay, w, wm):
    # D_w(wm) = G1(w) / |cos theta_w| * D(wm) * |w . wm|
    return _G1(ax, ay, w) / _abs(w[2]) * _D(ax, ay, wm) * _abs(_dot(w, wm))


@_outputs(())
def tr_D(ax, ay, wm):
    """pbrt-v4 ``TrowbridgeReitzDistribution::D(wm)``."""
    batch, _, (a, b), (m,), _ = _prep([ax, ay], [wm])
    return _out(batch, _D(a, b, m))


@_outputs(())
def tr_lambda(ax, ay, w):
    """pbrt-v4 ``TrowbridgeReitzDistribution::Lambda(w)``."""
    batch, _, (a, b), (v,), _ = _prep([ax, ay], [w])
    return _out(batch, _lambda(a, b, v))


@_outputs(())
def tr_G1(ax, ay, w):
    """pbrt-v4 ``TrowbridgeReitzDistribution::G1(w)`` = 1 / (1 + Lambda(w))."""
    batch, _, (a, b), (v,), _ = _prep([ax, ay], [w])
    return _out(batch, _G1(a, b, v))


@_outputs(())
def tr_G_correlated(ax, ay, wo, wi):
    """Height-correlated Smith ``1 / (1 + Lambda(wo) + Lambda(wi))`` (pbrt-v4 ``G``)."""
    batch, _, (a, b), (o, i), _ = _prep([ax, ay], [wo, wi])
    return _out(batch, _G(a, b, o, i, "correlated"))


@_outputs(())
def tr_G_separable(ax, ay, wo, wi):
    """Separable Smith ``G1(wo) G1(wi)`` (Mitsuba's G, without its back-facing test)."""
    batch, _, (a, b), (o, i), _ = _prep([ax, ay], [wo, wi])
    return _out(batch, _G(a, b, o, i, "separable"))


@_outputs(())
def tr_vndf_pdf(ax, ay, w, wm):
    """pbrt-v4 ``TrowbridgeReitzDistribution::PDF(w, wm)`` = G1(w)/|cos w| D(wm) |w . wm|."""
    batch, _, (a, b), (v, m), _ = _prep([ax, ay], [w, wm])
    return _out(batch, _vndf_pdf(a, b, v, m))


# ---------------------------------------------------------------------------------------------
# Fresnel
# ---------------------------------------------------------------------------------------------

def _fr_dielectric(cos_i, eta):
    dr, _ = _bk()
    c = _clamp(cos_i, -1.0, 1.0)
    inside = c < 0
    eta = _sel(inside, 1.0 / eta, eta)  # flip to the incident side's relative IOR
    c = _sel(inside, -c, c)
    sin2t = (1.0 - c * c) / (eta * eta)  # Snell: sin^2 t = sin^2 i / eta^2
    ct = _safe_sqrt(1.0 - sin2t)
    r_par = (eta * c - ct) / (eta * c + ct)
    r_perp = (c - eta * ct) / (c + eta * ct)
    # F = (r_par^2 + r_perp^2) / 2, = 1 under total internal reflection (sin^2 t >= 1)
    return _sel(sin2t >= 1.0, 1.0, 0.5 * (r_par * r_par + r_perp * r_perp))


# Complex arithmetic on (re, im) pairs of Float64 arrays.
def _cmul(a, b):
    return (a[0] * b[0] - a[1] * b[1], a[0] * b[1] + a[1] * b[0])


def _cdiv(a, b):
    d = b[0] * b[0] + b[1] * b[1]
    return ((a[0] * b[0] + a[1] * b[1]) / d, (a[1] * b[0] - a[0] * b[1]) / d)


def _csqrt(z):
    # principal square root: sqrt((|z| + re)/2) + i sign(im) sqrt((|z| - re)/2)
    dr, _ = _bk()
    r = dr.sqrt(z[0] * z[0] + z[1] * z[1])
    re = _safe_sqrt((r + z[0]) * 0.5)
    im = _safe_sqrt((r - z[0]) * 0.5)
    return (re, _sel(z[1] < 0, -im, im))


def _cnorm2(z):
    return z[0] * z[0] + z[1] * z[1]


def _fr_complex(cos_i, eta, k):
    c = _clamp(cos_i, 0.0, 1.0)
    n = (eta, k)                                                 # eta~ = eta + i k
    sin2t = _cdiv((1.0 - c * c, 0.0 * c), _cmul(n, n))           # sin^2 t = sin^2 i / eta~^2
    ct = _csqrt((1.0 - sin2t[0], -sin2t[1]))                     # cos t = sqrt(1 - sin^2 t)
    nc = (n[0] * c, n[1] * c)
    nct = _cmul(n, ct)
    r_par = _cdiv((nc[0] - ct[0], nc[1] - ct[1]), (nc[0] + ct[0], nc[1] + ct[1]))
    r_perp = _cdiv((c - nct[0], -nct[1]), (c + nct[0], nct[1]))
    return 0.5 * (_cnorm2(r_par) + _cnorm2(r_perp))              # F = (|r_par|^2 + |r_perp|^2)/2


# Conductor Fresnel approximations (bsdfkit ``Conductor(fresnel=...)``), restated from the papers.
F82_COS = 1.0 / 7.0  # F82-tint's fitting cosine (theta ~ 81.79 deg), where mu (1 - mu)^6 peaks


def _f0_conductor(eta, k):
    # normal-incidence reflectance of eta + i k: |(eta~ - 1) / (eta~ + 1)|^2
    return ((eta - 1.0) * (eta - 1.0) + k * k) / ((eta + 1.0) * (eta + 1.0) + k * k)


def _schlick(c, f0):
    m = 1.0 - c
    return f0 + (1.0 - f0) * (m * m * m * m * m)  # Schlick 1994: F0 + (1 - F0)(1 - mu)^5


def _fr_schlick_conductor(cos_i, eta, k):
    return _schlick(_clamp(cos_i, 0.0, 1.0), _f0_conductor(eta, k))


def _fr_f82_conductor(cos_i, eta, k):
    c = _clamp(cos_i, 0.0, 1.0)
    f0 = _f0_conductor(eta, k)
    mb = 1.0 - F82_COS
    # Hoffman 2019 / Kutz et al. 2021: F = Schlick(mu) - a mu (1 - mu)^6, with a fitted so that
    # F(mu_bar) = FrComplex(mu_bar): a = (Schlick(mu_bar) - F_exact(mu_bar)) / (mu_bar (1 - mu_bar)^6)
    mu_bar = F82_COS + 0.0 * eta
    a = (_schlick(mu_bar, f0) - _fr_complex(mu_bar, eta, k)) / (F82_COS * mb ** 6)
    m = 1.0 - c
    return _clamp(_schlick(c, f0) - a * c * (m * m * m * m * m * m), 0.0, 1.0)  # clamped to [0, 1]


_CONDUCTOR_FRESNEL = {"exact": _fr_complex, "schlick": _fr_schlick_conductor, "f82": _fr_f82_conductor}


def _fresnel_fn(fresnel):
    if fresnel not in _CONDUCTOR_FRESNEL:
        raise ValueError(f"fresnel must be one of {list(_CONDUCTOR_FRESNEL)}, got {fresnel!r}")
    return _CONDUCTOR_FRESNEL[fresnel]


@_outputs(())
def fr_dielectric(cos_i, eta):
    """pbrt-v4 ``FrDielectric(cos_i, eta)``: unpolarised dielectric Fresnel reflectance; ``cos_i
    < 0`` means the incident direction is inside (eta is inverted), 1 under TIR. Elementwise
    numpy broadcasting of ``cos_i`` and ``eta``."""
    batch, n, fs, _, _ = _prep([cos_i, eta])
    return _out(batch, _fr_dielectric(*fs))


@_outputs(())
def fr_complex(cos_i, eta, k):
    """pbrt-v4 ``FrComplex(cos_i, eta + i k)``: conductor Fresnel reflectance, ``cos_i`` clamped
    to [0, 1]. Elementwise numpy broadcasting (pass ``cos[..., None]`` with RGB ``eta``/``k``)."""
    batch, n, fs, _, _ = _prep([cos_i, eta, k])
    return _out(batch, _fr_complex(*fs))


@_outputs(())
def fr_schlick_conductor(cos_i, eta, k):
    """Schlick 1994 with the exact normal-incidence reflectance of ``eta + i k``:
    ``F0 + (1 - F0)(1 - cos)^5``, ``F0 = ((eta-1)^2 + k^2) / ((eta+1)^2 + k^2)``, ``cos_i`` clamped
    to [0, 1]. Elementwise numpy broadcasting."""
    batch, n, fs, _, _ = _prep([cos_i, eta, k])
    return _out(batch, _fr_schlick_conductor(*fs))


@_outputs(())
def fr_f82_conductor(cos_i, eta, k):
    """F82-tint conductor Fresnel (Hoffman 2019; Kutz et al. 2021): Schlick minus
    ``a cos (1 - cos)^6`` with ``a`` fitted to ``FrComplex`` at ``cos = 1/7``, clamped to [0, 1].
    Elementwise numpy broadcasting."""
    batch, n, fs, _, _ = _prep([cos_i, eta, k])
    return _out(batch, _fr_f82_conductor(*fs))


def conductor_fresnel(cos_i, eta, k, fresnel="exact"):
    """``fr_complex`` / ``fr_schlick_conductor`` / ``fr_f82_conductor`` by name, RGB: ``cos_i``
    of any shape, ``eta``/``k`` scalar or ``(3,)`` -> ``cos_i.shape + (3,)``."""
    fn = {"exact": fr_complex, "schlick": fr_schlick_conductor, "f82": fr_f82_conductor}
    if fresnel not in fn:
        raise ValueError(f"fresnel must be one of {list(fn)}, got {fresnel!r}")
    c = np.asarray(cos_i, dtype=np.float64)[..., None]
    return fn[fresnel](c, np.broadcast_to(np.asarray(eta, np.float64), (3,)),
                       np.broadcast_to(np.asarray(k, np.float64), (3,)))


# ---------------------------------------------------------------------------------------------
# Models
# ---------------------------------------------------------------------------------------------

@_outputs((3,))
def conductor_f(eta, k, ax, ay, wo, wi, masking="correlated", fresnel="exact"):
    """pbrt-v4 ``ConductorBxDF::f`` (rough GGX conductor, cosine excluded), RGB ``(..., 3)``.

    ``eta``, ``k``: ``(..., 3)`` (typically ``(3,)``); ``ax``, ``ay`` scalars or arrays;
    ``masking``: ``"correlated"`` (pbrt) or ``"separable"`` (Mitsuba); ``fresnel``: ``"exact"``
    (pbrt's ``FrComplex``), ``"schlick"`` or ``"f82"`` (bsdfkit's approximation knob, see
    ``conductor_fresnel``). Zero unless ``wo`` and ``wi`` are strictly in the same hemisphere
    (either side), zero for smooth alphas."""
    masking = _masking(masking)
    fr = _fresnel_fn(fresnel)
    batch, n, (a, b), (o, i), (e, kk) = _prep([ax, ay], [wo, wi], [eta, k])
    smooth, a, b = _max_alpha_rules(a, b)
    co, ci = o[2], i[2]
    wm = _add(o, i)
    len2 = _dot(wm, wm)
    ok = (co * ci > 0) & ~smooth & (len2 > 0)                    # SameHemisphere, non-delta, |wm|>0
    wm = _scale(wm, 1.0 / _bk()[0].sqrt(_sel(ok, len2, 1.0)))
    g = _D(a, b, wm) * _G(a, b, o, i, masking) / (4.0 * ci * co)  # f = D G F / (4 cos_i cos_o)
    cos_h = _abs(_dot(o, wm))
    f = tuple(_sel(ok, g * fr(cos_h, e[c], kk[c]), 0.0) for c in range(3))
    return _out3(batch, f)


@_outputs(())
def conductor_pdf(ax, ay, wo, wi, fresnel="exact"):
    """pbrt-v4 ``ConductorBxDF::PDF``: ``D_wo(wm) / (4 |wo . wm|)`` with ``wm = normalize(wo + wi)``
    faced to +z; 0 unless same hemisphere, for smooth alphas or when ``wo + wi = 0``.
    ``fresnel`` is accepted (and checked) for symmetry with ``conductor_f``: visible-normal
    sampling does not depend on the Fresnel term."""
    _fresnel_fn(fresnel)
    dr, _ = _bk()
    batch, n, (a, b), (o, i), _ = _prep([ax, ay], [wo, wi])
    smooth, a, b = _max_alpha_rules(a, b)
    wm = _add(o, i)
    len2 = _dot(wm, wm)
    ok = (o[2] * i[2] > 0) & ~smooth & (len2 > 0)
    wm = _scale(wm, 1.0 / dr.sqrt(_sel(ok, len2, 1.0)))
    wm = _scale(wm, _sel(wm[2] < 0, -1.0, 1.0))                  # FaceForward(wm, +z)
    return _out(batch, _sel(ok, _vndf_pdf(a, b, o, wm) / (4.0 * _abs(_dot(o, wm))), 0.0))


@_outputs((), ())
def dielectric_f_pdf(eta, ax, ay, wo, wi, mode="radiance", masking="correlated"):
    """pbrt-v4 rough ``DielectricBxDF::f`` and ``::PDF`` (all lobes enabled).

    ``eta`` (scalar or array) = IOR inside / outside (may be < 1). Returns ``(f (...), pdf
    (...))``; f is grey. Includes the generalised half vector ``wm = etap wi + wo`` faced to +z,
    the back-facing-microfacet discard, the refraction Jacobian and, in radiance mode, the
    ``1/etap^2`` factor on transmission. Smooth alphas or ``eta == 1`` give f = pdf = 0 (pbrt's
    delta branch); ``wi.z == 0`` or ``wo.z == 0`` give 0."""
    masking = _masking(masking)
    radiance = _is_radiance(mode)
    dr, _ = _bk()
    batch, n, (et, a, b), (o, i), _ = _prep([eta, ax, ay], [wo, wi])
    smooth, a, b = _max_alpha_rules(a, b)
    co, ci = o[2], i[2]
    reflect = co * ci > 0
    etap = _sel(reflect, 1.0, _sel(co > 0, et, 1.0 / et))
    wm = _add(_scale(i, etap), o)                                # generalised half vector
    len2 = _dot(wm, wm)
    ok = ~smooth & (et != 1.0) & (ci != 0) & (co != 0) & (len2 > 0)
    wm = _scale(wm, 1.0 / dr.sqrt(_sel(ok, len2, 1.0)))
    wm = _scale(wm, _sel(wm[2] < 0, -1.0, 1.0))                  # FaceForward(wm, +z)
    dwi, dwo = _dot(wm, i), _dot(wm, o)
    ok &= ~((dwi * ci < 0) | (dwo * co < 0))                     # discard back-facing microfacets
    F = _fr_dielectric(dwo, et)
    D = _D(a, b, wm)
    G = _G(a, b, o, i, masking)
    vpdf = _vndf_pdf(a, b, o, wm)
    # reflection: f = D G F / |4 cos_i cos_o|, pdf = D_wo(wm) / (4 |wo.wm|) * F
    f_r = D * G * F / _abs(4.0 * ci * co)
    p_r = vpdf / (4.0 * _abs(dwo)) * F
    # transmission: f = D (1-F) G |wi.wm wo.wm / (cos_i cos_o (wi.wm + wo.wm/etap)^2)| [/etap^2]
    denom = (dwi + dwo / etap) ** 2
    f_t = D * (1.0 - F) * G * _abs(dwi * dwo / (ci * co * denom))
    if radiance:
        f_t = f_t / (etap * etap)
    p_t = vpdf * _abs(dwi) / denom * (1.0 - F)                   # pdf = D_wo(wm) |wi.wm|/denom * T
    f = _sel(ok, _sel(reflect, f_r, f_t), 0.0)
    pdf = _sel(ok, _sel(reflect, p_r, p_t), 0.0)
    return _out(batch, f, pdf)


@_outputs((3,), ())
def diffuse_f_pdf(R, wo, wi):
    """pbrt-v4 ``DiffuseBxDF``: f = R/pi and pdf = |cos wi|/pi if same hemisphere, else 0."""
    batch, n, _, (o, i), (r,) = _prep([], [wo, wi], [R])
    same = o[2] * i[2] > 0
    f = tuple(_sel(same, r[c] * INV_PI, 0.0) for c in range(3))
    pdf = _sel(same, _abs(i[2]) * INV_PI, 0.0)
    return _out3(batch, f), _out(batch, pdf)


@_outputs((3,), ())
def diffuse_transmission_f_pdf(R, T, wo, wi):
    """pbrt-v4 ``DiffuseTransmissionBxDF``: f = R/pi in the same hemisphere else T/pi;
    pdf = |cos wi|/pi * (pr or pt)/(pr + pt) with pr = max(R), pt = max(T) (0 if both 0).
    ``R``, ``T``: ``(..., 3)``. Returns ``(f (..., 3), pdf (...))``."""
    batch, n, _, (o, i), (r, t) = _prep([], [wo, wi], [R, T])
    same = o[2] * i[2] > 0                                        # SameHemisphere (strict)
    f = tuple(_sel(same, r[c], t[c]) * INV_PI for c in range(3))
    pr = _sel(r[0] > r[1], r[0], r[1])
    pr = _sel(pr > r[2], pr, r[2])
    pt = _sel(t[0] > t[1], t[0], t[1])
    pt = _sel(pt > t[2], pt, t[2])
    tot = pr + pt
    frac = _sel(same, pr, pt) / _sel(tot > 0, tot, 1.0)
    pdf = _sel(tot > 0, frac * _abs(i[2]) * INV_PI, 0.0)
    return _out3(batch, f), _out(batch, pdf)


@_outputs(())
def thin_dielectric_R(cos_o, eta):
    """pbrt-v4 ``ThinDielectricBxDF`` slab reflectance: R = FrDielectric(|cos_o|, eta),
    R' = R + T^2 R / (1 - R^2) if R < 1 (T' = 1 - R' is the pass-through probability)."""
    batch, n, (c, et), _, _ = _prep([cos_o, eta])
    r = _fr_dielectric(_abs(c), et)
    t = 1.0 - r
    return _out(batch, _sel(r < 1.0, r + t * t * r / (1.0 - r * r), r))
