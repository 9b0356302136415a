"""Float64 reference of Filament's terms and material models, written with Dr.Jit.

Independent of the bsdfkit C++ core (cpp/include/bsdfkit/bxdfs/filament.h) and of Mitsuba: every
function restates a formula of Filament's document ("Physically Based Rendering in Filament",
cited "doc §") or shaders (``surface_brdf.fs``, ``surface_shading_model_*.fs``,
``surface_shading_lit.fs``, ``common_material.fs``) as summarised in
``/work/shared/research/pbrt_filament.md`` §4, in double precision on Dr.Jit's LLVM backend
(``drjit.llvm.Float64``). Where the document and the shaders write a term differently the
document's closed form is used here (e.g. D_GGX = a^2 / (pi ((NoH^2 (a^2 - 1) + 1)^2)) rather
than the shader's k form, and the GGX D has no cutoff), so that the two implementations share
neither code nor arithmetic.

Public functions take and return float64 numpy arrays (inputs broadcast with numpy rules):

* terms: :func:`D_GGX`, :func:`D_GGX_Anisotropic`, :func:`D_Charlie`, :func:`D_Ashikhmin`,
  :func:`V_SmithGGXCorrelated`, :func:`V_SmithGGXCorrelated_Fast`,
  :func:`V_SmithGGXCorrelated_Anisotropic`, :func:`V_Kelemen`, :func:`V_Neubelt`,
  :func:`F_Schlick`, :func:`Fd_Lambert`, :func:`Fd_Burley`, :func:`Fd_Wrap`,
  :func:`f0ClearCoatToSurface`;
* models: :func:`standard_f`, :func:`cloth_f` (f with the cosine excluded, one-sided: 0 unless
  wo.z > 0 and wi.z > 0), taking a ``bsdfkit.FilamentStandard`` / ``FilamentCloth`` (only its
  parameters are read) and the DFG table (``bsdfkit.filament.dfg_lut``: the *values* are shared,
  the bilinear lookup is re-implemented here);
* :func:`dfg_quadrature`: the DFG table's three integrals by a Gauss-Legendre product rule in
  the NDF's own CDF coordinates (the library uses quasi-Monte Carlo visible-normal sampling).

``dr.maximum``/``dr.minimum`` are avoided (selects instead), as in ``drjit_models``.
"""
import numpy as np

from . import _drjit_backend

__all__ = [
    "D_GGX", "D_GGX_Anisotropic", "D_Charlie", "D_Ashikhmin", "V_SmithGGXCorrelated",
    "V_SmithGGXCorrelated_Fast", "V_SmithGGXCorrelated_Anisotropic", "V_Kelemen", "V_Neubelt",
    "F_Schlick", "Fd_Lambert", "Fd_Burley", "Fd_Wrap", "f0ClearCoatToSurface",
    "standard_params", "standard_f", "cloth_f", "dfg_quadrature",
]

MIN_N_DOT_V = 1e-4                       # common_material.fs MIN_N_DOT_V
MIN_PERCEPTUAL_ROUGHNESS = {"desktop": 0.045, "mobile": 0.089}  # common_material.fs
CHARLIE_SIN2_FLOOR = 0.0078125           # brdf.fs D_Charlie / D_Ashikhmin: 2^-7
PI = np.pi

def _bk():
    """(dr, Dr.Jit array module), shared with the other references; the AD module while
    bsdfkit.testing.drjit_grad traces a call."""
    from . import drjit_models as _dm
    if _dm._TRACE is not None:
        import drjit.llvm.ad as B
        return _drjit_backend()[0], B
    return _drjit_backend()


# Parameters may be Dr.Jit arrays (width 1, with gradients: bsdfkit.testing.drjit_grad) or
# numbers; these helpers take either.
def _is_dr(x):
    return hasattr(x, "numpy") and not isinstance(x, np.ndarray)


def _val(x):
    """The plain value of a number or a width-1 Dr.Jit array."""
    return float(x.numpy()[0]) if _is_dr(x) else float(x)


def _mx(a, b):
    return _sel(a > b, a, b) if (_is_dr(a) or _is_dr(b)) else float(max(a, b))


def _mn(a, b):
    return _sel(a < b, a, b) if (_is_dr(a) or _is_dr(b)) else float(min(a, b))


def _num(x):
    """A Dr.Jit array as is, a number as a Python float (a numpy scalar times a Dr.Jit array
    would turn the product into a numpy array)."""
    return x if _is_dr(x) else float(x)


def _rgb3(x):
    """An RGB parameter as a list of 3 numbers (or Dr.Jit arrays)."""
    if isinstance(x, (list, tuple)) and any(_is_dr(v) for v in x):
        return list(x)
    a = np.broadcast_to(np.asarray(x, dtype=np.float64), (3,))
    return [float(v) for v in a]


def _F(a):
    dr, B = _bk()
    return B.Float64(np.ascontiguousarray(a, dtype=np.float64).reshape(-1))


def _sel(m, a, b):
    return _bk()[0].select(m, a, b)


def _clamp(x, lo, hi):
    return _sel(x < lo, lo, _sel(x > hi, hi, x))


def _sqrt(x):
    return _bk()[0].sqrt(x)


def _pow(x, y):
    dr = _bk()[0]
    return _sel(x > 0, dr.exp(y * dr.log(_sel(x > 0, x, 1.0))), 0.0)


def _apply(fn, *args):
    """numpy args (broadcast) -> Dr.Jit Float64 -> fn -> numpy of the broadcast shape."""
    dr, _ = _bk()
    arrs = np.broadcast_arrays(*[np.asarray(a, dtype=np.float64) for a in args])
    shape = arrs[0].shape
    if arrs[0].size == 0:
        return np.zeros(shape)
    r = fn(*[_F(a) for a in arrs])
    dr.eval(r)
    return np.asarray(r.numpy(), dtype=np.float64).reshape(shape)


# ---------------------------------------------------------------------------------- terms
# Each private _x works on Dr.Jit arrays; the public X wraps it for numpy.

def _D_GGX(a, NoH):
    # doc "Normal distribution function": D = a^2 / (pi ((n.h)^2 (a^2 - 1) + 1)^2)
    a2 = a * a
    d = NoH * NoH * (a2 - 1.0) + 1.0
    return a2 / (PI * d * d)


def _D_GGX_Anisotropic(at, ab, ToH, BoH, NoH):
    # doc "Anisotropic specular BRDF": D = 1 / (pi at ab ((t.h/at)^2 + (b.h/ab)^2 + (n.h)^2)^2)
    s = (ToH / at) ** 2 + (BoH / ab) ** 2 + NoH * NoH
    return 1.0 / (PI * at * ab * s * s)


def _D_Charlie(a, NoH):
    # doc "Cloth specular BRDF" / brdf.fs D_Charlie: (2 + 1/a) sin^(1/a)(theta_h) / (2 pi),
    # sin^2 = max(1 - NoH^2, 2^-7)
    s2 = 1.0 - NoH * NoH
    s2 = _sel(s2 > CHARLIE_SIN2_FLOOR, s2, CHARLIE_SIN2_FLOOR)
    return (2.0 + 1.0 / a) * _pow(s2, 0.5 / a) / (2.0 * PI)


def _D_Ashikhmin(a, NoH):
    # doc "Cloth specular BRDF" (Neubelt's normalised velvet NDF):
    # 1 / (pi (1 + 4 a^2)) (1 + 4 exp(-cot^2 / a^2) / sin^4), sin^2 = max(1 - NoH^2, 2^-7)
    dr = _bk()[0]
    c2 = NoH * NoH
    s2 = 1.0 - c2
    s2 = _sel(s2 > CHARLIE_SIN2_FLOOR, s2, CHARLIE_SIN2_FLOOR)
    cot2 = c2 / s2
    return (1.0 + 4.0 * dr.exp(-cot2 / (a * a)) / (s2 * s2)) / (PI * (1.0 + 4.0 * a * a))


def _V_SmithGGXCorrelated(a, NoV, NoL):
    # doc "Geometric shadowing": V = 0.5 / (NoL sqrt(NoV^2 (1 - a^2) + a^2) + NoV sqrt(NoL^2 (1 - a^2) + a^2))
    a2 = a * a
    return 0.5 / (NoL * _sqrt(NoV * NoV * (1.0 - a2) + a2) + NoV * _sqrt(NoL * NoL * (1.0 - a2) + a2))


def _V_SmithGGXCorrelated_Fast(a, NoV, NoL):
    # doc "Geometric shadowing", approximation: 0.5 / (NoL (NoV (1 - a) + a) + NoV (NoL (1 - a) + a))
    return 0.5 / (NoL * (NoV * (1.0 - a) + a) + NoV * (NoL * (1.0 - a) + a))


def _V_SmithGGXCorrelated_Anisotropic(at, ab, ToV, BoV, ToL, BoL, NoV, NoL):
    # doc "Anisotropic specular BRDF": V = 1 / (2 (NoL L_v + NoV L_l)),
    # L_v = sqrt(at^2 (t.v)^2 + ab^2 (b.v)^2 + (n.v)^2)
    lv = _sqrt(at * at * ToV * ToV + ab * ab * BoV * BoV + NoV * NoV)
    ll = _sqrt(at * at * ToL * ToL + ab * ab * BoL * BoL + NoL * NoL)
    return 1.0 / (2.0 * (NoL * lv + NoV * ll))


def _V_Kelemen(LoH):
    # doc "Clear coat specular BRDF": V = 1 / (4 (l.h)^2)
    return 1.0 / (4.0 * LoH * LoH)


def _V_Neubelt(NoV, NoL):
    # doc "Cloth specular BRDF": 1 / (4 (NoL + NoV - NoL NoV))
    return 1.0 / (4.0 * (NoL + NoV - NoL * NoV))


def _F_Schlick(f0, f90, VoH):
    # doc "Fresnel": F = f0 + (f90 - f0) (1 - v.h)^5
    m = 1.0 - VoH
    return f0 + (f90 - f0) * (m * m * m * m * m)


def _Fd_Burley(a, NoV, NoL, LoH):
    # doc "Diffuse BRDF" (Burley 2012): F_Schlick(n.l, 1, f90) F_Schlick(n.v, 1, f90) / pi,
    # f90 = 0.5 + 2 a cos^2(theta_d), cos(theta_d) = l.h
    f90 = 0.5 + 2.0 * a * LoH * LoH
    return _F_Schlick(1.0, f90, NoL) * _F_Schlick(1.0, f90, NoV) / PI


def _Fd_Wrap(NoL, w):
    # doc "Cloth diffuse BRDF": <(n.l + w) / (1 + w)^2> (saturated), no 1/pi
    return _clamp((NoL + w) / ((1.0 + w) * (1.0 + w)), 0.0, 1.0)


def _f0_clear_coat(f0):
    # common_material.fs f0ClearCoatToSurface, desktop fit
    return _clamp(f0 * (f0 * (0.941892 - 0.263008 * f0) + 0.346479) - 0.0285998, 0.0, 1.0)


def D_GGX(alpha, NoH):
    """GGX / Trowbridge-Reitz NDF (doc "Normal distribution function")."""
    return _apply(_D_GGX, alpha, NoH)


def D_GGX_Anisotropic(at, ab, ToH, BoH, NoH):
    """Anisotropic GGX NDF (Burley 2012; doc "Anisotropic specular BRDF")."""
    return _apply(_D_GGX_Anisotropic, at, ab, ToH, BoH, NoH)


def D_Charlie(alpha, NoH):
    """Charlie sheen NDF (Estevez & Kulla 2017) with the shader's sin^2 >= 2^-7 floor."""
    return _apply(_D_Charlie, alpha, NoH)


def D_Ashikhmin(alpha, NoH):
    """Neubelt-normalised Ashikhmin velvet NDF with the shader's sin^2 >= 2^-7 floor."""
    return _apply(_D_Ashikhmin, alpha, NoH)


def V_SmithGGXCorrelated(alpha, NoV, NoL):
    """Height-correlated Smith visibility G / (4 NoV NoL) (Heitz 2014)."""
    return _apply(_V_SmithGGXCorrelated, alpha, NoV, NoL)


def V_SmithGGXCorrelated_Fast(alpha, NoV, NoL):
    """Hammon 2017's square-root-free approximation of V_SmithGGXCorrelated."""
    return _apply(_V_SmithGGXCorrelated_Fast, alpha, NoV, NoL)


def V_SmithGGXCorrelated_Anisotropic(at, ab, ToV, BoV, ToL, BoL, NoV, NoL):
    """Anisotropic height-correlated Smith visibility (Heitz 2014)."""
    return _apply(_V_SmithGGXCorrelated_Anisotropic, at, ab, ToV, BoV, ToL, BoL, NoV, NoL)


def V_Kelemen(LoH):
    """Kelemen 2001 visibility of the clear coat."""
    return _apply(_V_Kelemen, LoH)


def V_Neubelt(NoV, NoL):
    """Neubelt & Pettineo 2013 cloth visibility."""
    return _apply(_V_Neubelt, NoV, NoL)


def F_Schlick(f0, f90, VoH):
    """Schlick 1994 Fresnel with explicit f90."""
    return _apply(_F_Schlick, f0, f90, VoH)


def Fd_Lambert(shape_like):
    """1/pi, broadcast to the shape of ``shape_like``."""
    return np.full(np.shape(shape_like), 1.0 / PI)


def Fd_Burley(alpha, NoV, NoL, LoH):
    """Burley 2012 diffuse (doc "Diffuse BRDF")."""
    return _apply(_Fd_Burley, alpha, NoV, NoL, LoH)


def Fd_Wrap(NoL, w):
    """Energy-conserving wrapped diffuse, without 1/pi."""
    return _apply(_Fd_Wrap, NoL, w)


def f0ClearCoatToSurface(f0):
    """Filament's desktop polynomial fit of iorToF0(f0ToIor(f0), 1.5)."""
    return _apply(_f0_clear_coat, f0)


# ---------------------------------------------------------------------------------- DFG lookup

class _Lut:
    """Bilinear lookup on bsdfkit's end-point grid: node (j, i) at roughness j / (n - 1),
    NoV i / (n - 1)."""

    def __init__(self, lut):
        lut = np.asarray(lut, dtype=np.float64)
        if lut.ndim != 3 or lut.shape[0] != lut.shape[1] or lut.shape[2] != 3:
            raise ValueError(f"lut must have shape (n, n, 3), got {lut.shape}")
        self.n = lut.shape[0]
        self.flat = _F(lut)

    def row(self, r):
        """(j0, ty): the row and its weight (ty a Dr.Jit array carrying r's gradient if r has one)."""
        t = _mn(_mx(r * (self.n - 1), 0.0), self.n - 1.0)
        j0 = min(int(np.floor(_val(t))), self.n - 2)
        return j0, t - j0

    def __call__(self, r, NoV, c):
        dr, B = _bk()
        j0, ty = self.row(r)
        t = _clamp(NoV * (self.n - 1.0), 0.0, self.n - 1.0)
        i0f = dr.floor(t)
        i0f = _sel(i0f > self.n - 2.0, self.n - 2.0, i0f)
        tx = t - i0f
        i0 = B.UInt32(i0f)

        def g(j, i):
            return dr.gather(B.Float64, self.flat, (j * self.n + i) * 3 + c)

        a = g(j0, i0) * (1.0 - tx) + g(j0, i0 + 1) * tx
        b = g(j0 + 1, i0) * (1.0 - tx) + g(j0 + 1, i0 + 1) * tx
        return a * (1.0 - ty) + b * ty


# ---------------------------------------------------------------------------------- models

def _min_pr(v):
    return MIN_PERCEPTUAL_ROUGHNESS[v] if isinstance(v, str) else float(v)


def standard_params(model) -> dict:
    """The derived shading parameters of a ``FilamentStandard`` (surface_shading_lit.fs
    getPixelParams), in float64: f0, f90, diffuse color, roughnesses and alphas."""
    def num(x):
        return x if _is_dr(x) else float(x)
    base = _rgb3(model.base_color)
    metal, cc = num(model.metallic), num(model.clear_coat)
    min_pr = _min_pr(model.min_roughness)
    refl = num(model.reflectance)
    f0 = [b * metal + 0.16 * refl * refl * (1.0 - metal) for b in base]       # computeF0, computeDielectricF0
    if model.clear_coat_ior_change:                                           # CLEAR_COAT_IOR_CHANGE
        fit = [_mn(_mx(x * (x * (0.941892 - 0.263008 * x) + 0.346479) - 0.0285998, 0.0), 1.0) for x in f0]
        f0 = [x * (1.0 - cc) + y * cc for x, y in zip(f0, fit)]
    f90 = _mn(_mx(16.5 * (f0[0] + f0[1] + f0[2]), 0.0), 1.0) if model.f90 == "filament" else 1.0
    cc_pr = _mn(_mx(num(model.clear_coat_roughness), min_pr), 1.0)
    r = num(model.roughness)
    r = r * (1.0 - cc) + _mx(r, cc_pr) * cc                                   # base at least as rough as the coat
    r = _mn(_mx(r, min_pr), 1.0)
    a = r * r
    an = num(model.anisotropy)
    at, ab = _mx(a * (1.0 + an), min_pr ** 2), _mx(a * (1.0 - an), min_pr ** 2)  # Kulla 2017, MIN_ROUGHNESS
    s_pr = _mn(_mx(num(model.sheen_roughness), min_pr), 1.0)
    sheen = _rgb3(model.sheen_color)
    plain = not any(_is_dr(v) for v in f0 + sheen + [r, at, cc, s_pr])
    arr = (lambda v: np.asarray(v, dtype=np.float64)) if plain else (lambda v: v)
    return {"f0": arr(f0), "f90": f90, "diffuse_color": arr([b * (1.0 - metal) for b in base]), "roughness": r,
            "alpha": a, "at": at, "ab": ab, "anisotropic": _val(an) != 0.0, "clear_coat": cc, "cc_roughness": cc_pr,
            "cc_alpha": cc_pr * cc_pr, "sheen_color": arr(sheen), "sheen_roughness": s_pr, "sheen_alpha": s_pr * s_pr}


def _geometry(wo, wi):
    """Dr.Jit (wo, wi, h, masks) from numpy (N, 3) arrays."""
    dr, _ = _bk()
    o = [_F(wo[:, k]) for k in range(3)]
    i = [_F(wi[:, k]) for k in range(3)]
    hs = [o[k] + i[k] for k in range(3)]
    ln = _sqrt(hs[0] * hs[0] + hs[1] * hs[1] + hs[2] * hs[2])
    ok = (o[2] > 0) & (i[2] > 0) & (ln > 0)
    ln = _sel(ok, ln, 1.0)
    h = [x / ln for x in hs]
    return o, i, h, ok


def _dirs(wo, wi):
    wo = np.asarray(wo, dtype=np.float64)
    wi = np.asarray(wi, dtype=np.float64)
    wo, wi = np.broadcast_arrays(wo, wi)
    return wo.shape[:-1], wo.reshape(-1, 3), wi.reshape(-1, 3)


def _rgb_out(batch, cols):
    dr, _ = _bk()
    from . import drjit_models as _dm
    if _dm._TRACE is not None:
        _dm._TRACE.out(batch, cols, True)
    dr.eval(*cols)
    return np.stack([np.asarray(c.numpy(), dtype=np.float64) for c in cols], axis=-1).reshape(batch + (3,))


def standard_f(model, wo, wi, lut):
    """Filament standard-model f(wo, wi) (cosine excluded), RGB ``(..., 3)``.

    Assembly of surface_shading_model_standard.fs surfaceShading (per-light color / NoL):
    color = Fd + Fr Ec [(1 - Fc) with clear_coat_layering "doc"]; color = color (1 - max(sheen) z)
    + Fsheen; color = color (1 - Fc) + Frc. NoV = max(n.v, 1e-4), NoL, NoH, LoH saturated."""
    p = standard_params(model)
    batch, wo, wi = _dirs(wo, wi)
    if wo.shape[0] == 0:
        return np.zeros(batch + (3,))
    L = _Lut(lut)
    o, i, h, ok = _geometry(wo, wi)
    NoV = _sel(o[2] > MIN_N_DOT_V, o[2], MIN_N_DOT_V)                 # clampNoV
    NoL = _clamp(i[2], 0.0, 1.0)
    NoH = _clamp(h[2], 0.0, 1.0)
    LoH = _clamp(i[0] * h[0] + i[1] * h[1] + i[2] * h[2], 0.0, 1.0)
    a = p["alpha"]
    if p["anisotropic"]:
        D = _D_GGX_Anisotropic(p["at"], p["ab"], h[0], h[1], NoH)
        V = _V_SmithGGXCorrelated_Anisotropic(p["at"], p["ab"], o[0], o[1], i[0], i[1], NoV, NoL)
    else:
        D = _D_GGX(a, NoH)
        V = (_V_SmithGGXCorrelated_Fast if model.visibility == "fast" else _V_SmithGGXCorrelated)(a, NoV, NoL)
    fd = _Fd_Burley(a, NoV, NoL, LoH) if model.diffuse == "burley" else 1.0 / PI
    y = L(p["roughness"], NoV, 1)
    cc = p["clear_coat"]
    # a lobe of strength 0 is present when its strength is differentiated (a Dr.Jit leaf,
    # bsdfkit.testing.drjit_grad): its value is 0 there, its right derivative is not
    has_cc = _val(cc) > 0 or _is_dr(cc)
    Fc = _F_Schlick(0.04, 1.0, LoH) * cc
    sheen = p["sheen_color"]
    sheen_max = _mx(_mx(sheen[0], sheen[1]), sheen[2])
    has_sheen = _val(sheen_max) > 0 or _is_dr(sheen_max)
    if has_sheen:
        scale = 1.0 - sheen_max * L(p["sheen_roughness"], NoV, 2)
        scale = _sel(scale > 0, scale, 0.0)  # bsdfkit floors Filament's sheen scaling at 0 (z > 1 at grazing NoV)
        Ds = _D_Charlie(p["sheen_alpha"], NoH) * _V_Neubelt(NoV, NoL)
    Dc = _D_GGX(p["cc_alpha"], NoH) * _V_Kelemen(LoH) * Fc
    cols = []
    for c in range(3):
        f0 = _num(p["f0"][c])
        Fr = D * V * _F_Schlick(f0, p["f90"], LoH)
        if model.energy_compensation:
            Fr = Fr * (1.0 + f0 * (1.0 / y - 1.0))                     # energy compensation
        if model.clear_coat_layering == "doc" and has_cc:
            Fr = Fr * (1.0 - Fc)
        col = _num(p["diffuse_color"][c]) * fd + Fr
        if has_sheen:
            col = col * scale + _num(sheen[c]) * Ds
        if has_cc:
            col = col * (1.0 - Fc) + Dc
        cols.append(_sel(ok, col, 0.0))
    return _rgb_out(batch, cols)


def cloth_f(model, wo, wi, lut=None):
    """Filament cloth-model f(wo, wi) (cosine excluded), RGB ``(..., 3)``
    (surface_shading_model_cloth.fs): Fr = D_Charlie V_Neubelt sheen; Fd = base * diffuse, with a
    subsurface color * Fd_Wrap(NoL, 0.5) saturate(ssc + NoL) / NoL (Filament leaves NoL out)."""
    batch, wo, wi = _dirs(wo, wi)
    if wo.shape[0] == 0:
        return np.zeros(batch + (3,))
    min_pr = _min_pr(model.min_roughness)
    r = _mn(_mx(_num(model.roughness), min_pr), 1.0)   # parameters: numbers or Dr.Jit AD leaves (drjit_grad)
    a = r * r
    base = _rgb3(model.base_color)
    sheen = [b ** 0.5 for b in base] if model.sheen_color is None else _rgb3(model.sheen_color)
    o, i, h, ok = _geometry(wo, wi)
    NoV = _sel(o[2] > MIN_N_DOT_V, o[2], MIN_N_DOT_V)
    NoL = _clamp(i[2], 0.0, 1.0)
    NoH = _clamp(h[2], 0.0, 1.0)
    LoH = _clamp(i[0] * h[0] + i[1] * h[1] + i[2] * h[2], 0.0, 1.0)
    spec = _D_Charlie(a, NoH) * _V_Neubelt(NoV, NoL)
    fd = _Fd_Burley(a, NoV, NoL, LoH) if model.diffuse == "burley" else 1.0 / PI
    ss = None if model.subsurface_color is None else _rgb3(model.subsurface_color)
    if ss is not None:
        fd = fd * _Fd_Wrap(NoL, 0.5) / _sel(NoL > 0, NoL, 1.0)
    cols = []
    for c in range(3):
        d = base[c] * fd
        if ss is not None:
            d = d * _clamp(ss[c] + NoL, 0.0, 1.0)
        cols.append(_sel(ok, d + sheen[c] * spec, 0.0))
    return _rgb_out(batch, cols)


# ---------------------------------------------------------------------------------- DFG quadrature

def dfg_quadrature(nov, roughness, n=256):
    """The DFG table's (x, y, z) at (NoV, perceptual roughness) by Gauss-Legendre quadrature.

    Coordinates: the NDF's own CDF u (GGX: cos^2(theta_h) = (1 - u) / (1 + (a^2 - 1) u); Charlie:
    sin(theta_h) = u^(a / (2 a + 1)), without the shader's floor) and the azimuth phi of h, in
    which D(h) cos(theta_h) dw_h = du dphi / (2 pi), so that the integral of f <NoL> over l =
    reflect(v, h) is the integral of 4 V NoL VoH / NoH du dphi / (2 pi). Both integration ranges
    end exactly where l reaches the horizon (NoL = 2 VoH NoH - NoV = 0): phi in [0, phi_c(theta_h)]
    (doubled by symmetry) and u up to the theta_h at which phi_c vanishes, so the rule never
    straddles the kink; u = 1 - s^2 with the rule in s removes the 1 / NoH near-singularity. ``n`` nodes per axis; ``nov``, ``roughness`` broadcast; returns (..., 3)."""
    dr, B = _bk()
    nov, roughness = np.broadcast_arrays(np.asarray(nov, dtype=np.float64), np.asarray(roughness, dtype=np.float64))
    shape = nov.shape
    xg, wg = np.polynomial.legendre.leggauss(int(n))
    t01, w01 = 0.5 * (xg + 1.0), 0.5 * wg
    out = np.zeros(shape + (3,))
    for idx in np.ndindex(shape):
        mu, r = float(nov[idx]), float(roughness[idx])
        a = r * r
        if a == 0.0:
            out[idx] = ((1 - mu) ** 5, 1.0, 0.0)
            continue
        sv = np.sqrt(max(0.0, 1 - mu * mu))

        def cos_phi_c(c):  # azimuth of h at which NoL = 0, for cos(theta_h) = c (+-inf when NoV = 1)
            with np.errstate(divide="ignore", invalid="ignore"):
                return (mu / (2.0 * c) - mu * c) / (sv * np.sqrt(np.maximum(1.0 - c * c, 1e-300)))

        # smallest valid cos(theta_h): cos_phi_c(c) = 1, by bisection on [mu / 2, 1]
        lo, hi = 0.5 * mu, 1.0
        for _ in range(200):
            m = 0.5 * (lo + hi)
            lo, hi = (m, hi) if cos_phi_c(m) >= 1.0 else (lo, m)
        c_star = hi
        res = []
        for kind in ("ggx", "charlie"):
            # u = 1 - s^2, s in [sqrt(1 - u_c), 1]: near the horizon 1 - u ~ cos^2(theta_h), so
            # the 1 / NoH of the integrand becomes smooth in s (du = 2 s ds)
            if kind == "ggx":
                u_c = (1 - c_star ** 2) / (1 + c_star ** 2 * (a * a - 1.0))
            else:
                u_c = (1 - c_star ** 2) ** ((2.0 * a + 1.0) / (2.0 * a))
            s_c = np.sqrt(max(0.0, 1.0 - u_c))
            sv_ = s_c + (1.0 - s_c) * t01
            u = 1.0 - sv_ * sv_
            wu = (1.0 - s_c) * w01 * 2.0 * sv_
            if kind == "ggx":
                c = np.sqrt(np.clip((1.0 - u) / (1.0 + (a * a - 1.0) * u), 0.0, 1.0))
            else:
                st = u ** (a / (2.0 * a + 1.0))
                c = np.sqrt(np.clip(1.0 - st * st, 0.0, 1.0))
            phi_c = np.arccos(np.clip(cos_phi_c(c), -1.0, 1.0))
            C = np.repeat(c, len(t01))
            PHI = (phi_c[:, None] * t01[None, :]).reshape(-1)
            W = (wu[:, None] * phi_c[:, None] * w01[None, :]).reshape(-1) * (2.0 / (2.0 * np.pi))
            S = np.sqrt(np.clip(1.0 - C * C, 0.0, 1.0))
            VoH = sv * S * np.cos(PHI) + mu * C
            NoL = 2.0 * VoH * C - mu
            keep = (NoL > 0) & (VoH > 0)
            NoLd, VoHd, NoHd = (_F(np.where(keep, q, 0.5)) for q in (NoL, VoH, C))
            if kind == "ggx":
                g = 4.0 * _V_SmithGGXCorrelated(a, mu, NoLd) * NoLd * VoHd / NoHd
                m5 = 1.0 - VoHd
                gx = g * m5 * m5 * m5 * m5 * m5
                dr.eval(g, gx)
                res += [np.sum(W * np.where(keep, np.asarray(gx.numpy()), 0.0)),
                        np.sum(W * np.where(keep, np.asarray(g.numpy()), 0.0))]
            else:
                g = 4.0 * _V_Neubelt(mu, NoLd) * NoLd * VoHd / NoHd
                dr.eval(g)
                res.append(np.sum(W * np.where(keep, np.asarray(g.numpy()), 0.0)))
        out[idx] = res
    return out
