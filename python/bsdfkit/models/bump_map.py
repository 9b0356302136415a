"""``BumpMap``: a model evaluated in the shading frame of a height field's gradient (Mitsuba 3
``bumpmap``), directions in and out staying in the geometric local frame; ``height_gradient``: the
uv gradient of a height image as Mitsuba's bilinear ``bitmap`` texture computes it."""
from __future__ import annotations

import numpy as np

from .._arrays import broadcast_batch
from . import _mitsuba_export as _me
from ._composite_core import array_param
from .composite import _model
from .normal_map import _rcross, _rnorm, _ShadingNormals

__all__ = ["BumpMap", "height_gradient", "bump_normals"]

_X, _Y = np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])
_WRAPS = ("repeat", "clamp", "mirror")


def _index(i, res, wrap):
    """Texel indices i wrapped into [0, res) as Dr.Jit's texture wrap modes do."""
    if wrap == "repeat":
        return np.mod(i, res)
    if wrap == "clamp":
        return np.clip(i, 0, res - 1)
    m = np.mod(i, 2 * res)   # mirror: 0 .. res-1, then res-1 .. 0
    return np.where(m >= res, 2 * res - 1 - m, m)


def height_gradient(height, uv, wrap_mode="repeat"):
    """(dh/du, dh/dv) of a one-channel height image at ``uv``, as Mitsuba 3's ``bitmap`` texture
    with ``filter_type="bilinear"`` computes it (``eval_1_grad``): texel (row j, column i) is
    centred at uv ((i + 0.5) / W, (j + 0.5) / H), the height is bilinear between texel centres,
    and the gradient is that interpolant's, in uv units (W and H times the per-texel differences).

    height: (H, W) array (rows along v). uv: (..., 2). wrap_mode: "repeat" (Mitsuba's default),
    "clamp" or "mirror". Returns two float64 arrays of shape ``uv.shape[:-1]``, to pass as
    ``BumpMap(model, dh_du, dh_dv)`` (Mitsuba's ``to_uv`` transform is not applied: transform uv
    first)."""
    h = np.asarray(height, dtype=np.float64)
    if h.ndim != 2 or h.size == 0:
        raise ValueError(f"height: expected a non-empty (H, W) array (one channel, rows along v), got shape {h.shape}")
    if not np.all(np.isfinite(h)):
        j = int(np.argmax(~np.isfinite(h).ravel()))
        raise ValueError(f"height: entries must be finite; the first bad one is at index "
                         f"{tuple(int(k) for k in np.unravel_index(j, h.shape))}")
    uv = array_param(uv, "uv", tail=(2,))
    if wrap_mode not in _WRAPS:
        raise ValueError(f"wrap_mode: must be one of {_WRAPS} (Mitsuba bitmap's), got {wrap_mode!r}")
    rows, cols = h.shape
    x, y = uv[..., 0] * cols - 0.5, uv[..., 1] * rows - 0.5   # Dr.Jit Texture: texel centres at +0.5
    x0, y0 = np.floor(x), np.floor(y)
    wx, wy = x - x0, y - y0   # weights of the upper neighbours (Mitsuba bilinear_weights' w1)
    i0, j0 = x0.astype(np.int64), y0.astype(np.int64)
    i0, i1 = _index(i0, cols, wrap_mode), _index(i0 + 1, cols, wrap_mode)
    j0, j1 = _index(j0, rows, wrap_mode), _index(j0 + 1, rows, wrap_mode)
    f00, f10, f01, f11 = h[j0, i0], h[j0, i1], h[j1, i0], h[j1, i1]
    # Mitsuba bitmap eval_1_grad: df/dx = w0y (f10 - f00) + w1y (f11 - f01), df/dy likewise; times resolution
    dx = (1 - wy) * (f10 - f00) + wy * (f11 - f01)
    dy = (1 - wx) * (f01 - f00) + wx * (f11 - f10)
    return dx * cols, dy * rows


def bump_normals(dh_du, dh_dv, scale=1.0, dp_du=None, dp_dv=None):
    """The bumped shading normals (..., 3) in the local frame (z up), Mitsuba 3's ``bumpmap``
    frame: dp/du' = dp/du with its normal (z) component replaced by scale dh/du (Mitsuba:
    dp_du + n (grad_u - n . dp_du); pbrt-v4's BumpMap adds the gradient to dp/du and also a
    displacement times dn/du, which Mitsuba and we drop: the base surface's normal is constant in
    the local frame), likewise dp/dv'; n = normalize(dp/du' x dp/dv'), negated if it points below
    the surface (Mitsuba: flipped to the geometric normal's side). dp_du, dp_dv default to the x
    and y axes (a flat uv-parameterized patch), where n = normalize(-scale dh/du, -scale dh/dv, 1)."""
    gu, gv = np.multiply(scale, dh_du), np.multiply(scale, dh_dv)   # Mitsuba: grad_uv = scale * eval_1_grad
    du = _X if dp_du is None else np.asarray(dp_du, np.float64)
    dv = _Y if dp_dv is None else np.asarray(dp_dv, np.float64)
    shape = np.broadcast_shapes(np.shape(gu), np.shape(gv), du.shape[:-1], dv.shape[:-1])
    a, b = np.empty(shape + (3,)), np.empty(shape + (3,))
    a[..., :2], a[..., 2] = du[..., :2], gu
    b[..., :2], b[..., 2] = dv[..., :2], gv
    n = _rcross(a, b)   # Mitsuba bumpmap: n = normalize(cross(dp_du', dp_dv'))
    n /= _rnorm(n)
    return np.where(n[..., 2:] < 0, -n, n)   # Mitsuba: n[dot(si.n, n) < 0] *= -1


def _tangent(x, name):
    return None if x is None else array_param(x, name, tail=(3,))


class BumpMap(_ShadingNormals):
    """A model evaluated in the shading frame of a height field's gradient (Mitsuba 3 ``bumpmap``).

    The height field h(u, v) enters through its uv derivatives at each element, ``dh_du`` and
    ``dh_dv`` (floats, or arrays broadcasting against the call's batch shape: per element), times
    ``scale``. The surface's dp/du and dp/dv in the local frame (z is the surface normal) are
    ``dp_du`` and ``dp_dv``, (3,) or (..., 3) per element; by default the x and y axes (a flat
    patch parameterized by uv, u along x). Mitsuba's ``bumpmap`` frame, step by step:

    * dp/du' = dp/du with its z component replaced by scale dh/du, dp/dv' likewise (Mitsuba:
      dp_du + n (scale dh/du - n . dp_du)). pbrt-v4's ``BumpMap`` adds a displacement times dn/du,
      the derivative of the base normal; Mitsuba drops it (the base normal is constant over an
      element here), and so do we; a constant height offset changes nothing.
    * The shading normal n = normalize(dp/du' x dp/dv'), negated if it points below the surface.
      With the default dp/du, dp/dv: n = normalize(-scale dh/du, -scale dh/dv, 1).
    * The frame's s axis is dp/du projected perpendicular to n, s = normalize(dp/du - n (n . dp/du))
      (NormalMap projects the x axis: the same with the default dp/du), t = n x s.

    Then everything is NormalMap's rule (``help(bsdfkit.NormalMap)``): Mitsuba 3.9's
    ``flip_invalid_normals`` and ``use_shadowing_function`` (``shadowing``), no light leaks (f = pdf
    = 0 where wi lies on different sides of the geometric and the shading normal), f the model's in
    the shading frame times |wi . n_s| / |wi . n_g| (times Estevez et al. 2019's G(wi)), pdf the
    model's, and the adjoint in TransportMode.Importance (the cosine ratio and G on wo). So a
    bump-mapped white Lambertian reflects at most 1 in Radiance mode, and the class does not
    declare ``energy_conserving`` or ``reciprocal``. A zero gradient (with the default dp/du) is
    the model itself, bit for bit.

    From a height image: ``dh_du, dh_dv = bsdfkit.models.bump_map.height_gradient(height, uv)``
    (Mitsuba's bilinear ``bitmap`` gradient at each element's uv), or ``BumpMap.from_height``.

    Parameters
    ----------
    model : BxDF or str
        The model evaluated in the shading frame.
    dh_du, dh_dv : float or numpy.ndarray, default 0
        The height's derivatives in u and v, per element (Mitsuba: the texture's eval_1_grad).
    scale : float or numpy.ndarray, default 1
        Multiplies the gradient (Mitsuba's ``scale``).
    dp_du, dp_dv : array_like (3,) or (..., 3), optional
        The surface's position derivatives in the local frame (default: x and y axes); their
        tangential (x, y) parts must not be parallel.
    flip_invalid_normals : bool, default True
        Mitsuba's rule: the shading normal is flipped where wo sees it from the other side.
    shadowing : bool, default True
        Estevez et al. 2019's shadow terminator term.
    """

    __slots__ = ()
    description = "A model in the shading frame of a height field's gradient (Mitsuba bumpmap)"
    examples = {"bumped diffuse": "bump_map [diffuse 0.8] 0.6 -0.4",
                "bumped rough gold, skewed uv": "bump_map [conductor metal=Au alpha=0.3 masking=separable] 1.5 0.5 "
                                                "scale=0.5 dp_du=1,0.2,0 dp_dv=-0.3,2,0",
                "flat (exports to Mitsuba)": "bump_map [plastic 0.5 alpha=0.2 masking=separable] 0 0 scale=2 "
                                             "shadowing=false"}
    mitsuba = "bumpmap"

    def __init__(self, model, dh_du=0.0, dh_dv=0.0, scale=1.0, dp_du=None, dp_dv=None, flip_invalid_normals=True,
                 shadowing=True):
        """A BumpMap: the parameters are described in the class docstring (``help(bsdfkit.BumpMap)``);
        a non-finite entry raises ValueError naming the parameter and the first bad index."""
        for name, v in (("flip_invalid_normals", flip_invalid_normals), ("shadowing", shadowing)):
            if not isinstance(v, (bool, np.bool_)):
                raise TypeError(f"{name}: expected True or False, got {v!r}")
        model = _model(model, "model")
        du, dv = array_param(dh_du, "dh_du"), array_param(dh_dv, "dh_dv")
        sc = array_param(scale, "scale")
        pu, pv = _tangent(dp_du, "dp_du"), _tangent(dp_dv, "dp_dv")
        names = ("dh_du", "dh_dv", "scale", "dp_du", "dp_dv")
        shapes = (np.shape(du), np.shape(dv), np.shape(sc), () if pu is None else pu.shape[:-1],
                  () if pv is None else pv.shape[:-1])
        shape = broadcast_batch(names, *shapes)
        if pu is not None or pv is not None:
            tu = np.broadcast_to(_X if pu is None else pu, shape + (3,))[..., :2]
            tv = np.broadcast_to(_Y if pv is None else pv, shape + (3,))[..., :2]
            cz = tu[..., 0] * tv[..., 1] - tu[..., 1] * tv[..., 0]
            bad = ~(np.abs(cz) > 1e-9 * np.linalg.norm(tu, axis=-1) * np.linalg.norm(tv, axis=-1))
            if bad.any():
                i = int(np.argmax(bad.ravel()))
                idx = tuple(int(j) for j in np.unravel_index(i, shape)) if shape else ()
                raise ValueError(f"dp_du, dp_dv: their tangential (x, y) parts must be nonzero and not parallel (the "
                                 f"surface's uv parameterization is degenerate there); the first bad pair, at index "
                                 f"{idx}, is {tu.reshape(-1, 2)[i].tolist()} and {tv.reshape(-1, 2)[i].tolist()}")
        super().__init__(model=model, dh_du=du, dh_dv=dv, scale=sc, dp_du=pu, dp_dv=pv,
                         flip_invalid_normals=bool(flip_invalid_normals), shadowing=bool(shadowing))

    @classmethod
    def from_height(cls, model, height, uv, scale=1.0, wrap_mode="repeat", **kwargs):
        """A BumpMap of the height image ``height`` ((H, W), rows along v) read at each element's
        ``uv`` ((..., 2)) as Mitsuba's bilinear ``bitmap`` texture does (``height_gradient``);
        other keywords (dp_du, dp_dv, flip_invalid_normals, shadowing) as the constructor's."""
        du, dv = height_gradient(height, uv, wrap_mode)
        return cls(model, du, dv, scale=scale, **kwargs)

    def _param_arrays(self):
        p = self._params
        n = bump_normals(p["dh_du"], p["dh_dv"], p["scale"], p["dp_du"], p["dp_dv"])
        out = {"normals": n}
        if p["dp_du"] is not None:
            out["tangent"] = p["dp_du"]
        return out

    def _flat(self) -> bool:
        p = self._params
        return not any(isinstance(p[k], np.ndarray) for k in ("dh_du", "dh_dv", "scale")) and \
            p["dh_du"] == 0 and p["dh_dv"] == 0

    def describe(self) -> str:
        p = self._params
        if any(isinstance(p[k], np.ndarray) for k in ("dh_du", "dh_dv", "scale")):
            txt = "map"
        else:
            txt = f"({p['scale'] * p['dh_du']:.2g}, {p['scale'] * p['dh_dv']:.2g})"
        return f"BumpMap {type(self.model).__name__}, grad h={txt}"

    def to_mitsuba(self, approximate: bool = False) -> dict:
        """``bumpmap`` with ``scale``, ``flip_invalid_normals``, ``use_shadowing_function`` and the
        model's dictionary, for a zero gradient with the default dp/du, dp/dv only: its height
        texture is a one-texel ``bitmap`` (an in-memory ``mi.Bitmap``, so the ``mitsuba`` package
        is needed). A nonzero or per-element gradient raises ValueError: Mitsuba differentiates a
        bitmap at each point's uv (there is no texture of a constant nonzero gradient), and takes
        dp/du, dp/dv from the mesh."""
        approximate = _me.check_approximate(approximate)
        p = self._params
        if not self._flat():
            raise ValueError("BumpMap.to_mitsuba: a nonzero or per-element height gradient has no Mitsuba dictionary "
                             "here (Mitsuba's bumpmap differentiates a bitmap texture at each point's uv); write the "
                             "height image as a bitmap and use Mitsuba's bumpmap directly")
        if p["dp_du"] is not None or p["dp_dv"] is not None:
            raise ValueError("BumpMap.to_mitsuba: dp_du / dp_dv are the mesh's in Mitsuba (not BSDF parameters)")
        try:
            import mitsuba as mi
        except ImportError:
            raise ValueError("BumpMap.to_mitsuba: the flat height texture is an in-memory mi.Bitmap; install the "
                             "mitsuba package") from None
        height = {"type": "bitmap", "bitmap": mi.Bitmap(np.zeros((1, 1, 1), np.float32)), "raw": True}
        return {"type": "bumpmap", "height": height, "scale": float(p["scale"]),
                "flip_invalid_normals": p["flip_invalid_normals"], "use_shadowing_function": p["shadowing"],
                "bsdf": self.model.to_mitsuba(approximate=approximate)}
