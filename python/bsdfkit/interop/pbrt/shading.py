"""pbrt-v4's shading-normal parameters of every material: ``"string normalmap"`` -> ``bk.NormalMap``
and ``"texture displacement"`` -> ``bk.BumpMap`` (pbrt-v4 ``materials.h``: ``NormalMap()``,
``BumpMap()``; a normal map wins over a displacement, as in ``Material::GetBSDF``)."""
from __future__ import annotations

import numpy as np

from ...textures import Texture, TextureBase
from .parser import _PbrtError
from .textures import PbrtLookup, float_value, image_path, is_texture
from .values import _check_texture, _pfail_param

__all__ = ["PbrtBumpGradient", "shading"]

#: pbrt-v4 BumpMap(): the finite-difference step in u and v without uv derivatives.
PBRT_BUMP_DELTA = 0.0005


class PbrtBumpGradient(TextureBase):
    """d(displacement)/du (``axis`` 0) or /dv (1) as pbrt-v4's ``BumpMap()`` takes it: the forward
    difference (d(uv + delta e) - d(uv)) / delta, delta = (|du/dx| + |du/dy|) / 2 with uv
    derivatives (per lookup), else 0.0005 (pbrt-v4's fallback)."""

    def __init__(self, tex, axis):
        if not isinstance(tex, TextureBase) or tex.channels != 1:
            raise TypeError("tex: expected a 1-channel texture (pbrt-v4's displacement is a float texture)")
        if axis not in (0, 1):
            raise ValueError(f"axis: expected 0 (u) or 1 (v), got {axis!r}")
        object.__setattr__(self, "tex", tex)
        object.__setattr__(self, "axis", int(axis))
        object.__setattr__(self, "channels", 1)

    def _args(self):
        return {"tex": self.tex, "axis": self.axis}

    def _lookup(self, uv, dx, dy):
        a = self.axis
        if dx is None:
            d = np.full(uv.shape[:-1], PBRT_BUMP_DELTA)
        else:
            d = 0.5 * (np.abs(dx[..., a]) + np.abs(dy[..., a]))
            d = np.where(d == 0, PBRT_BUMP_DELTA, d)
        shifted = uv.copy()
        shifted[..., a] += d
        h0 = self.tex._lookup(uv, dx, dy)
        h1 = self.tex._lookup(shifted, dx, dy)
        return (h1 - h0) / d[..., None]


def _normal_map_texture(rec, p, ctx):
    """pbrt-v4's normal map: the image read with the linear encoding, looked up bilinearly with
    repeat wrap at (u, 1 - v), decoded as normalize(2 rgb - 1) in the (dp/du, n) frame."""
    if p.type != "string" or len(p.values) != 1 or not isinstance(p.values[0], str) or not p.values[0]:
        _check_texture(rec, p)
        _pfail_param(rec, p, f"expected one \"string normalmap\" (an image file), got {p.type!r} {list(p.values)!r}")
    path = image_path(rec, p, p.values[0], ctx)
    try:
        tex = Texture(path, filter="bilinear", wrap="periodic", encoding="linear",
                      transform=[[1.0, 0.0, 0.0], [0.0, -1.0, 1.0]])
    except (OSError, ValueError, TypeError) as e:
        _pfail_param(rec, p, f"{path!r}: {e}")
    if tex.channels < 3:
        _pfail_param(rec, p, f"{path!r}: a normal map needs R, G and B channels, the image has {tex.channels}")
    return PbrtLookup("normal", tex)


def shading(rec, model, ctx):
    """``model`` under the material's normal map (``bk.NormalMap``) or displacement
    (``bk.BumpMap``), as pbrt-v4 shades it: no flip of invalid normals and no shadow-terminator
    term (pbrt-v4 has neither), so f times |wi . n_g| is pbrt's f times |wi . n_s|."""
    from ...models import BumpMap, NormalMap

    p = rec.params.get("normalmap")
    if p is not None:
        normals = _normal_map_texture(rec, p, ctx)
        try:
            return NormalMap(model, normals, flip_invalid_normals=False, shadowing=False)
        except (TypeError, ValueError) as e:
            _pfail_param(rec, p, f"bk.NormalMap: {e}")
    p = rec.params.get("displacement")
    if p is None:
        return model
    d = float_value(rec, "displacement", 0.0, ctx)
    if not is_texture(d):
        return model   # a constant offset: no bump on a flat element (PbrtMaterial.ignored)
    try:
        return BumpMap(model, PbrtBumpGradient(d, 0), PbrtBumpGradient(d, 1), flip_invalid_normals=False,
                       shadowing=False)
    except _PbrtError:
        raise
    except (TypeError, ValueError) as e:
        _pfail_param(rec, p, f"bk.BumpMap does not take this displacement texture ({e})")
