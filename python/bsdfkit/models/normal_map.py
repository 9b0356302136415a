"""``NormalMap``: a model evaluated in a frame tilted by tangent-space shading normals (Mitsuba 3
``normalmap``), directions in and out staying in the geometric local frame."""
from __future__ import annotations

import numpy as np

from .._enums import TransportMode
from . import _mitsuba_export as _me
from ._composite_core import array_param, child_eval, child_pdf, child_sample, empty_sample, put_sample
from .composite import _all, _Composite, _Flag, _model

__all__ = ["NormalMap", "shading_frame", "shadow_terminator"]

_IMP = int(TransportMode.Importance)


def _tan2(z):
    """tan^2 theta of a unit vector with cos theta = z (Mitsuba Frame3f::tan_theta_2)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.maximum(1 - z * z, 0) / (z * z)


def shadow_terminator(n, w):
    """Estevez et al. 2019 ("A Microfacet-Based Shadowing Function to Solve the Bump Terminator
    Problem", Ray Tracing Gems ch. 12) as Mitsuba's ``eval_shadow_terminator``: 2 / (1 + sqrt(1 +
    a2 tan^2 theta_w)) with a2 = min(tan^2 theta_n / 8, 1); ``n`` (the shading normal) and ``w`` in
    the geometric frame. 0 at the horizon."""
    a2 = np.minimum(0.125 * _tan2(n[..., 2]), 1.0)
    with np.errstate(invalid="ignore", over="ignore"):
        g = 2 / (1 + np.sqrt(1 + a2 * _tan2(w[..., 2])))
    return np.where(np.isfinite(g), g, 0.0)


def _rdot(a, b):
    """Row-wise a . b, summed x, y, z in that order: the same bits for a row whatever the number of
    rows (numpy's einsum / norm reductions may group the sums differently by array size)."""
    return a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1] + a[..., 2] * b[..., 2]


def _rnorm(a):
    return np.sqrt(_rdot(a, a))[..., None]


def _rcross(a, b):
    return np.stack([a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1], a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2],
                     a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]], axis=-1)


def shading_frame(n, wo, flip=True, tangent=None):
    """(s, t, n) of the shading frame of unit normals ``n`` (rows) for incident ``wo``, float64, as
    Mitsuba 3.9 ``normalmap``'s and ``bumpmap``'s ``frame``: with ``flip``, a normal on whose other
    side wo lies (wo.z (wo . n) <= 0) has its tangential part negated (Schüssler et al. 2017's
    flip); then s = normalize(d - n (n . d)) with d = ``tangent`` (rows; bumpmap: the surface's
    dp/du) or the x axis (normalmap: s = normalize(x - n n_x)), t = n x s. A tangent along n
    (nothing left after the projection) falls back to the x axis."""
    n = np.array(np.broadcast_to(n, np.broadcast_shapes(n.shape, wo.shape)), dtype=np.float64)
    if flip:
        bad = wo[:, 2] * _rdot(wo, n) <= 0
        n[bad, :2] *= -1
    n /= _rnorm(n)
    s = -n * n[:, :1]
    s[:, 0] += 1
    if tangent is not None:
        d = np.broadcast_to(tangent, n.shape).astype(np.float64)
        sd = d - n * _rdot(n, d)[:, None]   # Mitsuba bumpmap: s = dp_du - n (n . dp_du)
        ok = _rdot(sd, sd) > 1e-20 * _rdot(d, d)
        s = np.where(ok[:, None], sd, s)
    s /= _rnorm(s)
    return s, _rcross(n, s), n


def _local(v, frame):
    s, t, n = frame
    return np.stack([_rdot(v, s), _rdot(v, t), _rdot(v, n)], 1)


def _world(v, frame):
    """v (rows, shading frame) in the local frame: not renormalized (|w| = 1 to float64 rounding),
    so a shading frame equal to the local one gives v back bit for bit."""
    s, t, n = frame
    return v[:, :1] * s + v[:, 1:2] * t + v[:, 2:] * n


def _normals(x, convention):
    a = array_param(x, "normals", tail=(3,))
    items = a.reshape(-1, 3)
    bad = ~(np.abs(_rdot(items, items) - 1) <= 1e-4)
    if bad.any():
        i = int(np.argmax(bad))
        idx = tuple(int(j) for j in np.unravel_index(i, a.shape[:-1])) if a.ndim > 1 else ()
        raise ValueError(f"normals: must be unit vectors (|n|^2 = 1 within 1e-4; normalize them first); the first "
                         f"bad one, at index {idx}, is {items[i].tolist()} with |n| = {np.linalg.norm(items[i]):.6g}")
    up = items[:, 2] > 1e-6
    if not up.all():
        i = int(np.argmax(~up))
        idx = tuple(int(j) for j in np.unravel_index(i, a.shape[:-1])) if a.ndim > 1 else ()
        raise ValueError(f"normals: a tangent-space normal must point out of the surface (z > 0); the first bad one, "
                         f"at index {idx}, is {items[i].tolist()}")
    if convention not in ("opengl", "directx"):
        raise ValueError(f"convention: must be 'opengl' (y up, Mitsuba's and Blender's) or 'directx' (y down: the "
                         f"green channel flipped), got {convention!r}")
    if a.ndim == 1:
        a = np.array(a)
        a.setflags(write=False)
    return a


class _ShadingNormals(_Composite, register=False):
    """The shared rule of NormalMap and BumpMap (Mitsuba 3.9 ``normalmap`` / ``bumpmap``, described
    in NormalMap's docstring): a subclass's ``_param_arrays()`` gives ``normals`` (unit shading
    normals with z > 0 in the local frame, (3,) or rows) and optionally ``tangent`` (the direction
    the shading frame's s axis follows, default the x axis); its ``_params`` hold ``model``,
    ``flip_invalid_normals`` and ``shadowing``."""

    __slots__ = ()
    _param_tails = {"normals": (3,), "tangent": (3,)}
    energy_conserving = False
    exact_eval = _Flag(True, _all("exact_eval"))
    reciprocal = False
    two_sided = _Flag(True, _all("two_sided"))
    transmission = _Flag(False, _all("transmission"))
    delta_only = _Flag(False, _all("delta_only"))

    def _flags(self) -> int:
        return int(self.model.flags)

    def _frame(self, wo, P):
        n = P["_n"]
        w = np.broadcast_to(wo.astype(np.float64), (n, 3))
        t = P.get("tangent")
        return w, shading_frame(np.broadcast_to(P["normals"].astype(np.float64), (n, 3)), w,
                                self._params["flip_invalid_normals"], None if t is None else
                                np.broadcast_to(t.astype(np.float64), (n, 3)))

    def _factor(self, wo, wi, wo_p, wi_p, frame, md):
        """|w . n_s| / |w . n_g| (times G(w) with shadowing) of wi (Radiance) or wo (Importance)."""
        w, w_p = (wo, wo_p) if md == _IMP else (wi, wi_p)
        c = np.abs(w[:, 2])
        with np.errstate(divide="ignore", invalid="ignore"):
            r = np.where(c > 0, np.abs(w_p[:, 2]) / np.where(c > 0, c, 1), 0.0)
        if self._params["shadowing"]:
            r = r * shadow_terminator(frame[2], w)
        return r

    def _eval_pdf(self, wo, wi, md, lam, P, sf=None):
        wo64, frame = self._frame(wo, P)
        wi64 = np.broadcast_to(wi.astype(np.float64), wo64.shape)
        wo_p, wi_p = _local(wo64, frame), _local(wi64, frame)
        ok = wi64[:, 2] * wi_p[:, 2] > 0   # no light leaks (Mitsuba normalmap)
        dt = wo.dtype
        if sf is not None:
            return np.where(ok, child_pdf(self.model, wo_p.astype(dt), wi_p.astype(dt), md, sf, lam), 0).astype(dt)
        f = child_eval(self.model, wo_p.astype(dt), wi_p.astype(dt), md, lam).astype(np.float64)
        r = np.where(ok, self._factor(wo64, wi64, wo_p, wi_p, frame, md), 0.0)
        with np.errstate(over="ignore", invalid="ignore"):
            out = f * r[:, None]
        return np.where(np.isfinite(out) & (out <= np.finfo(dt).max), out, 0).astype(dt)

    def _eval_rows(self, wo, wi, md, lam, P, out=None):
        return self._eval_pdf(wo, wi, md, lam, P)

    def _pdf_rows(self, wo, wi, md, sf, lam, P, out=None):
        return self._eval_pdf(wo, wi, md, lam, P, sf)

    def _sample_rows(self, wo, uc, u, md, sf, lam, P, n):
        dt = uc.dtype
        rows = empty_sample(n, dt, 3 if lam is None else 4, lam is not None)
        wo64, frame = self._frame(wo, P)
        wo_p = _local(wo64, frame)
        s = child_sample(self.model, wo_p.astype(dt), uc, u, md, sf, lam)
        put_sample(rows, slice(None), s)
        wi_p = s.wi.astype(np.float64)
        wi = _world(wi_p, frame)
        ok = s.valid & (wi[:, 2] * wi_p[:, 2] > 0)   # Mitsuba: the sampled direction on one side of both
        r = np.where(ok, self._factor(wo64, wi, wo_p, wi_p, frame, md), 0.0)
        with np.errstate(over="ignore", invalid="ignore"):
            f = s.f.astype(np.float64) * r[:, None]
        ok &= np.all(np.isfinite(f) & (f <= np.finfo(dt).max), axis=1) & (r > 0)
        rows["wi"][...] = wi
        rows["f"][...] = np.where(ok[:, None], f, 0)
        rows["valid"][...] = ok
        inv = ~ok
        rows["wi"][inv] = (0, 0, 1)
        rows["pdf"][inv], rows["flags"][inv], rows["eta"][inv] = 0, 0, 1
        return rows


class NormalMap(_ShadingNormals):
    """A model evaluated in the shading frame of tangent-space normals (Mitsuba 3 ``normalmap``).

    model: the model. normals: unit vectors with z > 0 in the local (geometric) frame, (3,) or
    (..., 3) per element (broadcast against the call's batch). convention: ``"opengl"`` (y up, as
    given) or ``"directx"`` (y down: the normals' y is negated). ``wo``, ``wi`` and sampled
    directions stay in the geometric local frame. The shading frame of a normal n is Mitsuba's:
    s = normalize(x - n n_x), t = n x s (so anisotropic models keep their x axis as nearly as
    possible).

    The rule for the geometric vs the shading normal is Mitsuba 3.9's ``normalmap``:

    * ``flip_invalid_normals`` (default True): where wo lies on the other side of the shading
      normal than of the geometric one, the normal's tangential part is negated (Schüssler et al.
      2017), so wo always sees the shading surface from the side it sees the geometry.
    * No light leaks: f = pdf = 0 where wi lies on different sides of the geometric and the shading
      normal (Mitsuba: cos_theta(wo) cos_theta(perturbed_wo) > 0); sampled directions there are
      invalid.
    * f is the model's f in the shading frame times |wi . n_s| / |wi . n_g| (Mitsuba's eval includes
      the shading cosine; bsdfkit's excludes the geometric one), times Estevez et al. 2019's shadow
      terminator G(wi) when ``shadowing`` (Mitsuba's use_shadowing_function, default True); pdf is
      the model's (a solid-angle density does not depend on the frame).
    * TransportMode.Importance: the adjoint (Veach 1997, §5.3; pbrt-v4 BDPT's CorrectShadingNormal):
      the cosine ratio and G move to wo, f = f_model(Importance) |wo . n_s| / |wo . n_g| G(wo), the
      frame still built from wo. So f(wo, wi, Radiance) = f(wi, wo, Importance) wherever no flip
      occurs for either direction (the frames agree); a flip breaks it, as in Mitsuba.

    Consequences: a normal-mapped white Lambertian reflects less than 1 in Radiance mode (the
    cosine-weighted wedge where wi is above the shading but below the geometric surface is lost,
    and G < 1); in Importance mode the ratio |wo . n_s| / |wo . n_g| exceeds 1 at grazing wo, so
    the albedo can exceed 1 there (the known cost of shading normals): the class does not declare
    ``energy_conserving``, and it is not ``reciprocal`` (the flip and G are one-sided).

    Parameters
    ----------
    model : BxDF or str
        The model evaluated in the shading frame.
    normals : array_like, default (0, 0, 1)
        Unit tangent-space normals with z > 0, (3,) or (..., 3) per element.
    convention : {"opengl", "directx"}, default "opengl"
        "directx" negates the normals' y.
    flip_invalid_normals : bool, default True
        Mitsuba's rule: the shading normal is flipped where wo sees it from the other side.
    shadowing : bool, default True
        Estevez et al. 2019's shadow terminator term.
    """

    __slots__ = ()
    description = "A model in the shading frame of tangent-space normals (Mitsuba normalmap)"
    examples = {"tilted diffuse": "normal_map [diffuse 0.8] 0.36,-0.48,0.8",
                "tilted rough gold": "normal_map [conductor metal=Au alpha=0.3 masking=separable] 0,0.28,0.96",
                "no flip, no shadowing": "normal_map [plastic 0.5 alpha=0.2 masking=separable] 0.6,0,0.8 "
                                         "flip_invalid_normals=false shadowing=false"}
    mitsuba = "normalmap"

    def __init__(self, model, normals=(0.0, 0.0, 1.0), convention="opengl", flip_invalid_normals=True,
                 shadowing=True):
        """A NormalMap: the parameters are described in the class docstring (``help(bsdfkit.NormalMap)``);
        a non-unit normal raises ValueError naming ``normals`` and the first bad index."""
        for name, v in (("flip_invalid_normals", flip_invalid_normals), ("shadowing", shadowing)):
            if not isinstance(v, (bool, np.bool_)):
                raise TypeError(f"{name}: expected True or False, got {v!r}")
        super().__init__(model=_model(model, "model"), normals=_normals(normals, convention), convention=convention,
                         flip_invalid_normals=bool(flip_invalid_normals), shadowing=bool(shadowing))

    def _param_arrays(self):
        n = self._params["normals"]
        if self._params["convention"] == "directx":
            n = n * np.array([1.0, -1.0, 1.0])
        return {"normals": n}

    def describe(self) -> str:
        n = self._params["normals"]
        txt = "(" + ", ".join(f"{x:.2g}" for x in n) + ")" if n.ndim == 1 else "map"
        return f"NormalMap {type(self.model).__name__}, n={txt}"

    def to_mitsuba(self, approximate: bool = False) -> dict:
        """``normalmap`` with a constant ``rgb`` texture (n + 1) / 2 (the OpenGL normal: a DirectX
        one with y negated), ``flip_invalid_normals``, ``use_shadowing_function`` and the model's
        dictionary. Per-element normals raise ValueError (no uv mapping to write a bitmap with)."""
        approximate = _me.check_approximate(approximate)
        n = self._param_arrays()["normals"]
        if n.ndim != 1:
            raise ValueError("NormalMap.to_mitsuba: per-element normals have no Mitsuba dictionary here (Mitsuba "
                             "takes a bitmap texture at uv); export each element's NormalMap")
        return {"type": "normalmap", "normalmap": {"type": "rgb", "value": [float(x) for x in (n + 1) / 2]},
                "flip_invalid_normals": self._params["flip_invalid_normals"],
                "use_shadowing_function": self._params["shadowing"],
                "bsdf": self.model.to_mitsuba(approximate=approximate)}
