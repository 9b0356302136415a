"""Textured models: a model constructed with a texture (``bsdfkit.textures``) for a parameter.

``bk.Conductor.from_metal("Cu", alpha=bk.Texture("rough.png"))`` returns a :class:`Textured`
model: it records the model class and its arguments, and each call with ``uv=`` looks the
textures up and runs the model with per-element parameters (``at(uv)``), so the results are those
of per-element parameters looked up at the same uv, bit for bit. Nothing here is model-specific:
a class's constructor runs as usual on the looked-up arrays, so it validates them (naming the
parameter and the first bad index) and every parameter the class lists in ``varying_params``
takes a texture. Children of composites may be textured models too.
"""
from __future__ import annotations

import inspect

import numpy as np

from .._values import fmt_param, key_value
from ..textures import TextureBase, check_lookup
from .base import BxDF

__all__ = ["Textured", "has_texture"]

# uv at which a textured model is built once at construction (a 4 x 4 grid of texel-free points):
# its argument checks run there, and its flags are the union of the models there.
_PROBE_UV = np.stack(np.meshgrid((np.arange(4) + 0.37) / 4, (np.arange(4) + 0.61) / 4), -1).reshape(-1, 2)


def _textured_value(v) -> bool:
    if isinstance(v, (TextureBase, Textured)):
        return True
    return isinstance(v, (list, tuple)) and any(isinstance(x, (TextureBase, Textured)) for x in v)


def has_texture(args, kwargs) -> bool:
    """Whether constructor arguments hold a texture or a textured model (one level into lists)."""
    return any(_textured_value(v) for v in args) or any(_textured_value(v) for v in kwargs.values())


def _bind(cls, args, kwargs) -> dict:
    """The arguments by parameter name, as the constructor would see them (no defaults)."""
    sig = inspect.signature(cls)
    try:
        bound = sig.bind(*args, **kwargs)
    except TypeError as e:
        raise TypeError(f"{cls.__name__}: {e}") from None
    out = {}
    for name, v in bound.arguments.items():
        kind = sig.parameters[name].kind
        if kind is inspect.Parameter.VAR_KEYWORD:
            out.update(v)
        elif kind is inspect.Parameter.VAR_POSITIONAL:
            out.update({f"{name}[{i}]": x for i, x in enumerate(v)})
        else:
            out[name] = v
    return out


def _kinds(cls) -> dict:
    """{argument: 1 (a real) or 3 (an RGB)} of a model class: its ``varying_params``, and for a
    composite its per-element parameters' tails (``_param_tails``; others are reals)."""
    tails = getattr(cls, "_param_tails", None)
    if cls.varying_params or tails is None:
        return dict(cls.varying_params)
    return {k: 3 if t == (3,) else 1 for k, t in tails.items()}


def _as_param(values: np.ndarray, name: str, tex: TextureBase, kind) -> np.ndarray | float:
    """A texture's looked-up values (..., C) as the parameter ``name`` takes them: a real (kind
    1) from a 1-channel texture, an RGB (kind 3) from 1 (replicated), 3 or 4 channels (RGBA: the
    first three)."""
    c = values.shape[-1]
    if kind == 3:
        if c == 1:
            values = np.repeat(values, 3, axis=-1)
        elif c == 4:
            values = values[..., :3]
        elif c != 3:
            raise ValueError(f"{name}: an RGB parameter takes a texture of 1, 3 or 4 channels, got {c} ({tex!r})")
    elif c == 1:
        values = values[..., 0]
    else:
        raise ValueError(f"{name}: a real parameter takes a 1-channel texture, got {c} channels; pick one "
                         f"with Texture(..., channel=k) ({tex!r})")
    if values.ndim == 0:
        return float(values)
    values = np.ascontiguousarray(values)
    values.setflags(write=False)
    return values


class Textured(BxDF, register=False):
    """A model whose parameters (some of them) come from textures, looked up at ``uv``.

    Not built directly: constructing any model with a texture argument returns one. It keeps
    the model class (``model_class``) and the arguments; ``textures`` maps argument names to
    their textures. ``eval``, ``pdf``, ``sample``, ``albedo`` and ``eval_grad`` take ``uv=``
    (..., 2), broadcast with the directions, and optionally ``duvdx=``, ``duvdy=`` (filtered
    lookups); ``at(uv)`` is the model with the textures looked up (per-element parameters).

    Parameters
    ----------
    model_class : type
        The model class (``bk.Conductor``, ...), read-only.
    textures : dict
        {argument name: texture (or textured child model)}, read-only.

    Examples
    --------
    >>> import numpy as np, bsdfkit as bk
    >>> rough = bk.Texture(np.array([[0.125, 0.5], [0.25, 0.375]]), filter="nearest")
    >>> m = bk.Conductor.from_metal("Cu", alpha=rough)
    >>> m.textures
    {'alpha': Texture(source=[[[0.125], [0.5]], [[0.25], [0.375]]], filter='nearest')}
    >>> m.at([[0.25, 0.25], [0.75, 0.25]]).alpha_x.tolist()
    [0.125, 0.5]
    """

    def __init__(self, *a, **k):   # never called: models build these through BxDF.__new__
        raise TypeError("Textured is built by constructing a model with a texture argument, "
                        "e.g. bk.Diffuse(bk.Texture(img))")

    @classmethod
    def _of(cls, model_class, args, kwargs):
        self = object.__new__(cls)
        params = _bind(model_class, args, kwargs)
        object.__setattr__(self, "model_class", model_class)
        object.__setattr__(self, "_call", (tuple(args), dict(kwargs)))
        object.__setattr__(self, "_params", params)
        kinds = _kinds(model_class)
        if model_class.varying_params:   # a compiled model: only its per-element parameters take textures
            for name, v in params.items():
                if isinstance(v, TextureBase) and name not in kinds and name + "_x" not in kinds:
                    raise TypeError(f"{model_class.__name__}.{name}: takes one value for the whole material (a knob "
                                    f"or a count); it cannot be a texture (textures go to: {', '.join(kinds)})")
        # built once at a few uv: the constructor's checks run now (a knob given a texture, a
        # 3-channel texture for a real, values out of range there) rather than at the first call
        object.__setattr__(self, "_probe", self.at(_PROBE_UV))
        object.__setattr__(self, "_core", None)
        return self

    @property
    def textures(self) -> dict:
        """{argument name: texture} of the arguments given as textures (textured children of a
        composite are listed under the child's argument as their model)."""
        return {k: v for k, v in self._params.items() if _textured_value(v)}

    @property
    def varying(self) -> tuple:
        return tuple(self.textures)

    @property
    def flags(self):
        return self._probe.flags

    def at(self, uv, duvdx=None, duvdy=None) -> BxDF:
        """The model with every texture looked up at ``uv`` (..., 2): per-element parameters of
        shape uv.shape[:-1] (``(...)`` for a real, ``(..., 3)`` for an RGB)."""
        uv, duvdx, duvdy = check_lookup(uv, duvdx, duvdy)
        kinds = _kinds(self.model_class)

        def value(v, name):
            if isinstance(v, TextureBase):
                return _as_param(v._lookup(uv, duvdx, duvdy), name, v, kinds.get(name, 1))
            if isinstance(v, Textured):
                return v.at(uv, duvdx, duvdy)
            if isinstance(v, (list, tuple)) and _textured_value(v):
                return type(v)(value(x, f"{name}[{i}]") for i, x in enumerate(v))
            return v

        args, kwargs = self._call
        names = list(self._params)
        a = [value(v, names[i] if i < len(names) else str(i)) for i, v in enumerate(args)]
        k = {n: value(v, n) for n, v in kwargs.items()}
        return self.model_class(*a, **k)

    def _need_uv(self, uv):
        if uv is None:
            raise ValueError(f"uv: {self.model_class.__name__} has textured parameters "
                             f"({', '.join(self.textures)}); pass uv= (..., 2), or use the material at one texel, "
                             "m.at([u, v])")

    def _refuse_varying(self, what: str) -> None:
        if what.startswith("tradeoff"):
            what = "tradeoff (bk.simplify measures textured materials texel by texel)"
        raise NotImplementedError(
            f"{self.model_class.__name__}: {what} is not supported with textured parameters yet "
            f"({', '.join(self.textures)}); use the material at one texel, m.at([u, v]), or m.at(uv) per element")

    # the array API: look the textures up, then the model with per-element parameters
    def eval(self, wo, wi, mode=0, out=None, *, uv=None, duvdx=None, duvdy=None, **kw):
        self._need_uv(uv)
        return self.at(uv, duvdx, duvdy).eval(wo, wi, mode, out, **kw)

    def pdf(self, wo, wi, mode=0, sample_flags=3, out=None, *, uv=None, duvdx=None, duvdy=None, **kw):
        self._need_uv(uv)
        return self.at(uv, duvdx, duvdy).pdf(wo, wi, mode, sample_flags, out, **kw)

    def sample(self, wo, uc=None, u=None, *, uv=None, duvdx=None, duvdy=None, **kw):
        self._need_uv(uv)
        return self.at(uv, duvdx, duvdy).sample(wo, uc, u, **kw)

    def albedo(self, wo, n_samples: int = 65536, seed: int = 0, mode=0, *, uv=None, duvdx=None, duvdy=None, **kw):
        self._need_uv(uv)
        return self.at(uv, duvdx, duvdy).albedo(wo, n_samples, seed, mode, **kw)

    def eval_grad(self, wo, wi, params=None, mode=0, *, uv=None, duvdx=None, duvdy=None):
        self._need_uv(uv)
        return self.at(uv, duvdx, duvdy).eval_grad(wo, wi, params, mode)

    eval.__doc__, pdf.__doc__, sample.__doc__, albedo.__doc__ = (BxDF.eval.__doc__, BxDF.pdf.__doc__,
                                                                  BxDF.sample.__doc__, BxDF.albedo.__doc__)

    # value semantics: by the model class and its arguments, textures by content
    def _key(self):
        return (self.model_class.__name__,) + tuple(
            (k, v._key() if isinstance(v, (TextureBase, BxDF)) else
             tuple(x._key() if isinstance(x, (TextureBase, BxDF)) else key_value(x) for x in v)
             if isinstance(v, (list, tuple)) else key_value(v))
            for k, v in self._params.items())

    def __eq__(self, other):
        return type(other) is Textured and self._key() == other._key()

    def __hash__(self):
        return hash(self._key())

    def __repr__(self):
        def fmt(v):
            if isinstance(v, (TextureBase, BxDF)):
                return repr(v)
            if isinstance(v, (list, tuple)):
                return "[" + ", ".join(fmt(x) for x in v) + "]"
            return fmt_param(v)
        return f"{self.model_class.__name__}({', '.join(f'{k}={fmt(v)}' for k, v in self._params.items())})"

    def __reduce__(self):
        return (_construct, (self.model_class, *self._call))

    def describe(self) -> str:
        return f"{self.model_class.__name__} ({', '.join(self.textures)} textured)"

    def cost_family(self) -> str:
        return self._probe.cost_family()

    def to_mitsuba(self, approximate: bool = False, texture_dir=None) -> dict:
        """The Mitsuba 3 plugin dictionary, textures as ``bitmap`` dicts (image files by path;
        arrays written as EXR files into ``texture_dir``, else in-memory ``data`` tensors); what
        a bitmap cannot express raises NotImplementedError naming it
        (``bsdfkit.interop._mitsuba_textured_export``)."""
        from ..interop._mitsuba_textured_export import textured_to_mitsuba
        return textured_to_mitsuba(self, approximate, texture_dir)


def _construct(cls, args, kwargs):
    return cls(*args, **kwargs)
