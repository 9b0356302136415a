"""The model base class (array API, value semantics) and the parameter validation shared by every model."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import _core
from .._dask import dask_eval, is_dask_array
from .._enums import BxDFFlags, ReflTrans, TransportMode
from .._validate import bad_message as _bad_message  # noqa: F401  (re-exported for the models)
from .._validate import check_mode as _mode  # noqa: F401
from .._validate import check_real as _scalar  # noqa: F401
from .._validate import check_rgb as _rgb  # noqa: F401
from .._validate import check_sample_flags as _sflags  # noqa: F401
from .._validate import raise_bad as _raise_bad  # noqa: F401
from .._values import digest, fmt_param, key_value  # noqa: F401  (re-exported)
from . import _spectral
from . import registry as _registry

__all__ = ["roughness_to_alpha", "SampleResult", "BxDF"]


_MASKING = {"correlated": 0, "separable": 1}


def _alphas(alpha, alpha_x, alpha_y, varying=False):
    """(alpha_x, alpha_y) from either ``alpha`` (isotropic; None = 0, smooth) or both of
    ``alpha_x`` and ``alpha_y``: one of the pair alone would silently leave the other at 0, and
    ``alpha`` with the pair would silently ignore one of them. ``varying``: arrays (per element)
    are accepted."""
    if (alpha_x is None) != (alpha_y is None):
        given, missing = ("alpha_x", "alpha_y") if alpha_y is None else ("alpha_y", "alpha_x")
        raise ValueError(f"{missing}: give alpha_x and alpha_y together (only {given} was given), "
                         "or alpha alone for an isotropic lobe")
    if alpha_x is not None:
        if alpha is not None:
            raise ValueError("alpha: give either alpha (isotropic) or alpha_x and alpha_y (anisotropic), not both")
        return (_scalar(alpha_x, "alpha_x", lo=0.0, varying=varying),
                _scalar(alpha_y, "alpha_y", lo=0.0, varying=varying))
    a = 0.0 if alpha is None else _scalar(alpha, "alpha", lo=0.0, varying=varying)
    return a, a


#: The masking knob of the microfacet models (a modelling choice: which material it is).
def masking_knob(moot):
    return _registry.KnobDecl("masking", ("correlated", "separable"), "modelling",
                              "Smith masking-shadowing: height-correlated (pbrt-v4) or separable G1 G1 (Mitsuba 3)",
                              moot=moot)


def _masking(m) -> str:
    if m not in _MASKING:
        raise ValueError(f"masking: must be one of {sorted(_MASKING)}, got {m!r}")
    return m


#: The microfacet distributions (core/microfacet.h ``Distribution``).
DISTRIBUTIONS = ("ggx", "beckmann")


def _distribution(d) -> str:
    if not isinstance(d, str) or d not in DISTRIBUTIONS:
        raise ValueError(f"distribution: must be one of {list(DISTRIBUTIONS)}, got {d!r}")
    return d


def _sample_visible(v) -> bool:
    if not isinstance(v, (bool, np.bool_)):
        raise TypeError(f"sample_visible: expected True or False, got {v!r}")
    return bool(v)


def distribution_knob(moot):
    return _registry.KnobDecl("distribution", DISTRIBUTIONS, "modelling",
                              "microfacet distribution: Trowbridge-Reitz / GGX (pbrt-v4) or Beckmann "
                              "(Mitsuba 3's default)", moot=moot)


def microfacet_kw(p) -> dict:
    """The microfacet keywords of a parameter dict for its ``_core`` model."""
    return {"masking": _MASKING[p["masking"]], "distribution": p["distribution"],
            "sample_visible": p["sample_visible"]}


def is_smooth(p) -> bool:
    """pbrt-v4's ``EffectivelySmooth`` on a parameter dict with alpha_x / alpha_y (per-element
    alphas: whether every element is smooth)."""
    return bool(np.max(np.maximum(p["alpha_x"], p["alpha_y"]), initial=0.0) < 1e-3)


def fmt_value(v) -> str:
    """A number or an RGB triple, short (one number when the channels agree)."""
    v = np.asarray(v, dtype=np.float64)
    if v.ndim and np.allclose(v, v.flat[0]):
        v = v.flat[0]
    elif v.ndim > 1 or (v.ndim == 1 and v.size != 3):
        return "per element"
    if v.ndim == 0:
        return f"{float(v):.3g}"
    return "(" + ", ".join(f"{x:.2g}" for x in v) + ")"


def alpha_text(p) -> str:
    """``", smooth"``, ``", α=0.2"`` or ``", αx=.., αy=.."`` for a parameter dict with alphas."""
    ax, ay = p["alpha_x"], p["alpha_y"]
    if np.ndim(ax) or np.ndim(ay):
        return ", α per element"
    if max(ax, ay) < 1e-3:
        return ", smooth"
    dist = ", Beckmann" if p.get("distribution") == "beckmann" else ""
    if ax == ay:
        return f", α={ax:.3g}{dist}"
    return f", αx={ax:.3g}, αy={ay:.3g}{dist}"


def rgb_dict(v) -> dict:
    """A Mitsuba ``rgb`` texture of a scalar or RGB value."""
    a = np.broadcast_to(np.asarray(v, dtype=np.float64), (3,))
    return {"type": "rgb", "value": [float(x) for x in a]}


#: pbrt-v4 / Mitsuba 3 alpha floor of the rough microfacet lobes.
MIN_ALPHA = 1e-4


def roughness_to_alpha(roughness):
    """pbrt-v4's ``RoughnessToAlpha``: alpha = sqrt(roughness).

    pbrt-v4 applies it to ``roughness``/``uroughness``/``vroughness`` when ``remaproughness``
    is true (the default). pbrt-v4 issue #479 notes that r**2 would have been the perceptually
    linear choice; sqrt is kept for compatibility with pbrt scenes.

    Parameters
    ----------
    roughness : float or array_like
        pbrt's roughness, finite and >= 0.

    Returns
    -------
    float or numpy.ndarray
        alpha: a float for a scalar input, else a float64 array of the input's shape.

    Raises
    ------
    ValueError
        A roughness that is negative or not finite.

    Examples
    --------
    >>> import bsdfkit as bk
    >>> bk.roughness_to_alpha(0.09)
    0.3
    """
    r = np.asarray(roughness, dtype=np.float64)
    if not np.all(np.isfinite(r)) or np.any(r < 0):
        raise ValueError("roughness: must be finite and >= 0")
    out = np.sqrt(r)
    return float(out) if out.ndim == 0 else out


@dataclass(frozen=True)
class SampleResult:
    """Sampled directions and their values (``BxDF.sample``); arrays share the batch shape of
    the inputs.

    Attributes
    ----------
    wi : numpy.ndarray, shape (..., 3)
        Sampled directions (outward, local frame; world space when ``sample`` was given
        ``normal=``).
    f : numpy.ndarray, shape (..., 3)
        BSDF value (cosine excluded); (..., 4), one value per wavelength, in spectral mode.
    pdf : numpy.ndarray, shape (...)
        Solid-angle density, or the discrete probability for a specular lobe.
    flags : numpy.ndarray of uint8, shape (...)
        ``BxDFFlags`` of the sampled lobe.
    eta : numpy.ndarray, shape (...)
        Relative IOR along wi (1 for reflection).
    valid : numpy.ndarray of bool, shape (...)
        False where no sample exists (then f = pdf = 0, wi = (0, 0, 1), the shading normal, and
        eta = 1: every wi is a valid ``eval`` / ``pdf`` input).
    pdf_is_proportional : numpy.ndarray of bool, shape (...)
        True where pdf is only proportional to the density (the stochastic layered models).
    terminated : numpy.ndarray of bool or None
        Spectral mode: True where a refraction through a dispersive dielectric kept the first
        (hero) wavelength only (f of the others is 0; apply pbrt-v4's TerminateSecondary to the
        wavelength pdfs, ``bsdfkit.spectral.terminate_secondary``); None in RGB mode.
    """

    wi: np.ndarray
    f: np.ndarray
    pdf: np.ndarray
    flags: np.ndarray
    eta: np.ndarray
    valid: np.ndarray
    pdf_is_proportional: np.ndarray
    terminated: np.ndarray = None

    @property
    def weight(self) -> np.ndarray:
        """f |cos wi| / pdf, 0 where invalid (the Monte Carlo throughput weight); cos wi is to the
        shading normal (wi.z, or wi . normal of a world-space ``sample``)."""
        cos = self.__dict__.get("_cos_wi")
        with np.errstate(divide="ignore", invalid="ignore"):
            w = self.f * ((np.abs(self.wi[..., 2]) if cos is None else cos) / self.pdf)[..., None]
        return np.where(self.valid[..., None], w, 0.0).astype(self.f.dtype)


_RADIANCE = TransportMode.Radiance
_ALL = ReflTrans.All
_SAMPLE_FIELDS = ("wi", "f", "pdf", "flags", "eta", "valid", "pdf_is_proportional")


def _sample_result(arrays) -> SampleResult:
    """A SampleResult of the seven arrays (SampleResult field order), without the frozen
    dataclass's __init__ (seven object.__setattr__ calls): part of a small call's fixed cost."""
    r = object.__new__(SampleResult)
    r.__dict__.update(zip(_SAMPLE_FIELDS, arrays))
    return r


class BxDF:
    """Common array API of every model (pbrt-v4 conventions).

    Directions live in the local shading frame (z is the normal), are unit vectors and point
    away from the surface, both ``wo`` (towards the viewer) and ``wi``; with ``normal=`` (and
    ``tangent=``) per element they are world-space instead. ``eval`` excludes the
    cosine factor; ``pdf`` is per unit solid angle. Inputs broadcast with numpy rules over
    their leading axes. float32 inputs run float32 kernels, anything else real runs float64.

    Per-element parameters (spatially varying materials): the parameters a class lists in
    ``varying_params`` also take numpy arrays, ``(...)`` for a real and ``(..., 3)`` for an RGB
    value, broadcasting with the directions' leading axes; element i then gets exactly the values
    of the model built from element i's parameters (docs/howto/arrays.md).

    Models are immutable values: equal parameters compare and hash equal, ``eval(repr(m)) == m``
    (arrays of more than 12 values print as their shape and digest) and they pickle.

    Parameters
    ----------
    **params
        The model's parameters as its subclass constructor checked them (a subclass's own
        ``__init__`` takes the named parameters; ``BxDF`` itself is not built directly).

    Examples
    --------
    >>> import numpy as np, bsdfkit as bk
    >>> m = bk.Conductor.from_metal("Cu", alpha=0.2)
    >>> isinstance(m, bk.BxDF), m == bk.Conductor.from_metal("Cu", alpha=0.2)
    (True, True)
    >>> rough = np.array([[0.1, 0.3], [0.5, 0.7]])           # a 2 x 2 roughness map
    >>> sv = bk.Conductor.from_metal("Cu", alpha=rough)
    >>> f = sv.eval(bk.direction(0.3, 0.0), bk.direction(0.3, np.pi))   # one pair over the map
    >>> f.shape, bool(np.all(f[1, 0] == bk.Conductor.from_metal("Cu", alpha=0.5).eval(
    ...     bk.direction(0.3, 0.0), bk.direction(0.3, np.pi))))
    ((2, 2, 3), True)
    """

    _fields: tuple = ()
    __slots__ = ("_core", "_params")

    # ---- declarations read by the registry (see bsdfkit.models.registry); subclasses set them
    #: Short names accepted by the spec parser besides the class name.
    aliases: tuple = ()
    #: One-line description.
    description: str = ""
    #: Accuracy knobs (``KnobDecl``), most influential first; precision is every model's last knob.
    knobs: tuple = ()
    #: f is defined over the whole sphere of wo and wi, with no "below the surface" (a fibre, e.g.
    #: Hair): plots draw the whole sphere, and contracts that assume a hemispherical surface
    #: model (albedo over wo's hemisphere, cosine-weighted sampling) are gated on it.
    full_sphere: bool = False
    #: The parameters that take one value per element (issue 47): {name: 1 (a real) or 3 (RGB)},
    #: by the names the model stores (``params``). Such a parameter may be a numpy array of shape
    #: (...) or (..., 3) that broadcasts against the call's batch shape (the directions' shape
    #: without the last axis); the model's kernels then build each element's model from its
    #: values. Integer, table and knob parameters stay uniform.
    varying_params: dict = {}

    def __init_subclass__(cls, register: bool = True, **kwargs):
        super().__init_subclass__(**kwargs)
        if register:
            _registry.register(cls)

    def cost_family(self) -> str:
        """Cost-table family: the class plus the structural variant that selects a different
        compiled kernel (smooth/rough, optional lobes). Models override it."""
        return type(self).__name__

    def describe(self) -> str:
        """A short human-readable name, e.g. ``"Conductor Au, α=0.2"`` (legends and titles)."""
        if self.varying:
            return f"{type(self).__name__} ({', '.join(self.varying)} per element)"
        from .spec import to_spec
        rest = to_spec(self).split()[1:]
        return type(self).__name__ + (" " + ", ".join(rest) if rest else "")

    def to_mitsuba(self, approximate: bool = False) -> dict:
        """The Mitsuba 3 plugin dictionary (``mi.load_dict``) of this model. Raises
        NotImplementedError naming the reason when Mitsuba has no equivalent plugin (models that
        have a nearest one export it with ``approximate=True`` and a warning stating the
        difference; this one has none)."""
        raise NotImplementedError(f"{type(self).__name__}: Mitsuba 3 has no equivalent plugin")

    def __new__(cls, *args, **kwargs):
        # a texture among the arguments: a Textured model (looked up per call at uv=)
        if args or kwargs:
            from .textured import Textured, has_texture
            if has_texture(args, kwargs):
                return Textured._of(cls, args, kwargs)
        return object.__new__(cls)

    def __init__(self, **params):
        object.__setattr__(self, "_params", params)
        object.__setattr__(self, "_core", self._make_core())

    def _make_core(self):
        raise NotImplementedError

    @property
    def varying(self) -> tuple:
        """The parameters given per element (numpy arrays) in this model, in ``params`` order;
        ``()`` for a uniform model."""
        vp = type(self).varying_params
        return tuple(k for k, v in self._params.items()
                     if k in vp and isinstance(v, np.ndarray) and v.ndim >= (1 if vp[k] == 1 else 2))

    def _refuse_varying(self, what: str) -> None:
        """NotImplementedError for an operation that needs one uniform material."""
        if self.varying:
            raise NotImplementedError(
                f"{type(self).__name__}: {what} is not supported with per-element parameters yet "
                f"({', '.join(self.varying)}); build one model per parameter value")

    # ---- spectral form (core/bxdf.h `Spectral`): one generic construction for every model
    def _has_spectral_kernel(self) -> bool:
        """Whether the compiled model has a spectral form (``_core.<Name>Spectral``): read from
        ``_core``, not declared here."""
        return hasattr(_core, type(self._core).__name__ + "Spectral")

    def _spectral_inputs(self) -> dict:
        """The spectral form's inputs that are not a field's own value: a field's value computed
        from others (uplifted like the field), and the form's extra inputs (flags, numbers,
        tables), passed as they are. The few models with such inputs override it."""
        return {}

    def _spectral_core_kwargs(self) -> dict:
        """The spectral form's keyword arguments: the compiled RGB model's parameters (what
        stays wavelength-independent, and the colours' RGB projection)."""
        return self._core.params

    def _make_spectral_core(self):
        """``_core.<Name>Spectral`` of this model: each of its ``spectral_fields`` (declared by
        the C++ form) as a ``_core.SpectralParam`` of the field's value, uplifted by the field's
        kind, plus ``_spectral_inputs()``."""
        self._refuse_varying("spectral mode (wavelengths=)")
        cls = getattr(_core, type(self._core).__name__ + "Spectral")
        extra = dict(self._spectral_inputs())
        spectral = {name: _spectral.spectral_param(extra.pop(name) if name in extra else self._params[name], kind)
                    for name, kind in cls.spectral_fields}
        spectral.update(extra)
        return cls(spectral, **self._spectral_core_kwargs())

    # immutability, value semantics, pickling
    def __setattr__(self, k, v):
        raise AttributeError(f"{type(self).__name__} is immutable; build a new model instead")

    def __getattr__(self, k):
        params = object.__getattribute__(self, "_params")
        if k in params:
            return params[k]
        raise AttributeError(f"{type(self).__name__!s} has no attribute {k!r}")

    def _key(self):
        return tuple((k, key_value(v)) for k, v in self._params.items())

    def __eq__(self, other):
        return type(self) is type(other) and self._key() == other._key()

    def __hash__(self):
        return hash((type(self).__name__, self._key()))

    def __repr__(self):
        # Python's shortest round-trip float repr, not a rounded one: eval(repr(m)) == m (but for
        # arrays of more than 12 values, shown by shape and digest)
        args = ", ".join(f"{k}={fmt_param(v)}" for k, v in self._params.items())
        return f"{type(self).__name__}({args})"

    def __reduce__(self):
        return (_rebuild, (type(self), dict(self._params)))

    @property
    def flags(self) -> BxDFFlags:
        """The lobes this model has (``BxDFFlags``)."""
        return BxDFFlags(self._core.flags)

    # array API. Each op is one call of the compiled core's door (cpp/bindings/bind_model.h): it
    # takes the arguments as given, converts and checks what is not a plain array, words every
    # argument error and runs the kernels. Python only dispatches: spectral mode, Dask arrays.
    def eval(self, wo, wi, mode=TransportMode.Radiance, out=None, *, wavelengths=None, normal=None,
             tangent=None, uv=None, duvdx=None, duvdy=None) -> np.ndarray:
        """BSDF value f(wo, wi), cosine excluded, per RGB channel.

        Specular (delta) lobes evaluate to 0 for every given pair, as in pbrt-v4; use
        ``sample`` to reach them. Dask arrays of directions give a lazy Dask array (blockwise,
        bit-identical values; ``bsdfkit._dask``); ``pdf`` likewise.

        Memory layout: an (N, 3) direction array may be C-ordered (x y z per row) or
        Fortran-ordered, i.e. three contiguous component planes, the structure-of-arrays layout
        Mitsuba's kernels read: ``d.T`` of a (3, N) array ``d`` (no copy) or
        ``numpy.asfortranarray(w)``. Models with packet kernels read planes without transposing
        them (faster; README "Performance"), with bit-identical values. The result is
        Fortran-ordered (its ``.T`` is a (3, N) C-ordered view) when every full-length direction
        argument is, C-ordered otherwise (numpy's ``order='K'``); ``out`` may be either.

        Parameters
        ----------
        wo, wi : array_like, shape (..., 3)
            Unit directions in the local shading frame, both pointing away from the surface;
            their leading axes broadcast. float32 inputs run float32 kernels, other real
            inputs float64. Numpy or Dask arrays.
        mode : TransportMode or str, optional
            ``Radiance`` (default) or ``Importance`` (adjoint transport: differs for
            refraction).
        out : numpy.ndarray, optional
            Array of the result's shape and dtype to write into; it is returned.
        wavelengths : array_like, shape (..., 4), optional
            Wavelengths in nm in [360, 830], broadcast with the directions: spectral mode, one
            value per wavelength (docs/SPECTRAL.md).
        normal : array_like, shape (..., 3), optional
            World-space shading normals, per element (broadcast with the directions): ``wo`` and
            ``wi`` are then world-space and are rotated into each element's frame before the
            model runs (``bsdfkit.models._frames``; computed in float64, rounded to the
            directions' dtype). Unit within 1e-4 in ``|n|^2``.
        tangent : array_like, shape (..., 3), optional
            With ``normal``: the frame's x axis (anisotropic models), unit and perpendicular to
            the normal within 1e-4. Default: Duff et al. 2017's frame of the normal, Mitsuba 3's
            ``Frame3f(n)`` (the identity for n = (0, 0, 1)).
        uv : array_like, shape (..., 2), optional
            Texture coordinates, broadcast with the directions, for a model with textured
            parameters (``bsdfkit.textures``; required there); ignored by other models.
        duvdx, duvdy : array_like, shape (..., 2), optional
            With ``uv``: its screen-space derivatives, for filtered (MIP-mapped) lookups.

        Returns
        -------
        numpy.ndarray, shape (..., 3)
            f per RGB channel ((..., 4) per wavelength in spectral mode); a lazy Dask array when
            a direction argument is a Dask array.

        Raises
        ------
        ValueError
            A direction that is not a finite unit vector (``|w|^2`` within 1e-4 of 1), shapes
            that do not broadcast, a bad ``mode`` or ``out``; a bad ``normal`` or ``tangent``
            (not a finite unit vector, a tangent not perpendicular to the normal, a tangent
            without a normal), naming it and its first bad index.

        Examples
        --------
        >>> import numpy as np, bsdfkit as bk
        >>> m = bk.Conductor.from_metal("Cu", alpha=0.2)
        >>> wo = bk.direction(np.radians(30), 0.0)
        >>> m.eval(wo, bk.direction(np.radians(30), np.pi))   # the mirror direction
        array([2.507..., 1.632..., 1.346...])
        >>> m.eval(wo, bk.hemisphere_grid(9, 18)).shape
        (162, 3)
        >>> n = np.array([0.0, 0.6, 0.8])   # world space: a tilted normal, wo = wi = n is normal incidence
        >>> bool(np.allclose(m.eval(n, n, normal=n), m.eval([0, 0, 1.0], [0, 0, 1.0])))
        True
        """
        if normal is not None or tangent is not None:   # world space: rotate, then the local call
            from . import _frames
            return _frames.eval(self, wo, wi, mode, out, wavelengths, normal, tangent)
        if wavelengths is not None:
            return _spectral.eval(self, wo, wi, wavelengths, mode, out)
        if (type(wo) is not np.ndarray or type(wi) is not np.ndarray) and (is_dask_array(wo) or is_dask_array(wi)):
            return dask_eval(self, "eval", wo, wi, mode, out=out)  # a lazy Dask array, blockwise (bsdfkit._dask)
        return self._core.eval(wo, wi, mode, out)

    def pdf(self, wo, wi, mode=TransportMode.Radiance, sample_flags=ReflTrans.All, out=None, *,
            wavelengths=None, normal=None, tangent=None, uv=None, duvdx=None, duvdy=None) -> np.ndarray:
        """Solid-angle density of ``sample`` producing wi from wo; 0 for delta lobes.

        Directions may be (N, 3) Fortran-ordered planes, read without transposition, with
        bit-identical values (see ``eval``).

        Parameters
        ----------
        wo, wi : array_like, shape (..., 3)
            Unit directions in the local shading frame (as in ``eval``).
        mode : TransportMode or str, optional
            ``Radiance`` (default) or ``Importance``.
        sample_flags : ReflTrans, optional
            The lobes ``sample`` was restricted to (default ``ReflTrans.All``).
        out : numpy.ndarray, optional
            Array of the result's shape and dtype to write into; it is returned.
        wavelengths : array_like, shape (..., 4), optional
            The density of ``sample`` with those wavelengths (the first one's for a dispersive
            dielectric).
        normal : array_like, shape (..., 3), optional
            World-space shading normals, per element (broadcast with the directions): ``wo`` and
            ``wi`` are then world-space and are rotated into each element's frame before the
            model runs (``bsdfkit.models._frames``; computed in float64, rounded to the
            directions' dtype). Unit within 1e-4 in ``|n|^2``.
        tangent : array_like, shape (..., 3), optional
            With ``normal``: the frame's x axis (anisotropic models), unit and perpendicular to
            the normal within 1e-4. Default: Duff et al. 2017's frame of the normal, Mitsuba 3's
            ``Frame3f(n)`` (the identity for n = (0, 0, 1)).
        uv : array_like, shape (..., 2), optional
            Texture coordinates, broadcast with the directions, for a model with textured
            parameters (``bsdfkit.textures``; required there); ignored by other models.
        duvdx, duvdy : array_like, shape (..., 2), optional
            With ``uv``: its screen-space derivatives, for filtered (MIP-mapped) lookups.

        Returns
        -------
        numpy.ndarray, shape (...)
            The density per unit solid angle (a lazy Dask array for Dask directions).

        Raises
        ------
        ValueError
            As ``eval`` (including ``normal`` / ``tangent``); a ``sample_flags`` that is not a
            ``ReflTrans``.

        Examples
        --------
        >>> import numpy as np, bsdfkit as bk
        >>> m = bk.Conductor.from_metal("Cu", alpha=0.2)
        >>> float(m.pdf(bk.direction(np.radians(30), 0.0), bk.direction(np.radians(30), np.pi)))
        2.289...
        """
        if normal is not None or tangent is not None:
            from . import _frames
            return _frames.pdf(self, wo, wi, mode, sample_flags, out, wavelengths, normal, tangent)
        if wavelengths is not None:
            return _spectral.pdf(self, wo, wi, wavelengths, mode, sample_flags, out)
        if (type(wo) is not np.ndarray or type(wi) is not np.ndarray) and (is_dask_array(wo) or is_dask_array(wi)):
            return dask_eval(self, "pdf", wo, wi, mode, sample_flags, out=out)
        return self._core.pdf(wo, wi, mode, sample_flags, out)

    def sample(self, wo, uc=None, u=None, *, n=None, seed=None, mode=TransportMode.Radiance,
               sample_flags=ReflTrans.All, out=None, wavelengths=None, normal=None, tangent=None, uv=None,
               duvdx=None, duvdy=None) -> SampleResult:
        """Importance-sample wi given wo.

        Either pass the uniforms ``uc`` (...) (lobe choice) and ``u`` (..., 2) (direction), in
        [0, 1], broadcast with wo's leading axes (a Python float for ``uc`` is fine), or pass ``n``
        (number of samples) and an optional non-negative integer ``seed``: the batch shape is then
        broadcast(wo, (n,)) and the uniforms come from a counter-based hash of (seed, element
        index), the generator ``albedo`` uses, so the values do not depend on the thread count
        (``seed=None`` draws a seed from the system's entropy).
        ``out``: a SampleResult of this call's shapes and dtypes (e.g. an earlier result) to
        write into instead of allocating; it is returned.
        ``wavelengths`` (..., 4): spectral mode (f per wavelength, ``terminated``; see SampleResult).

        Parameters
        ----------
        wo : array_like, shape (..., 3)
            Unit outgoing directions in the local shading frame.
        uc : float or array_like, shape (...), optional
            Uniform in [0, 1] choosing the lobe; with ``u``, instead of ``n``.
        u : array_like, shape (..., 2), optional
            Uniforms in [0, 1] choosing the direction.
        n : int, optional
            Number of samples drawn from the counter-based generator (instead of ``uc``/``u``).
        seed : int, optional
            Non-negative seed of that generator; None draws one from the system's entropy.
        mode : TransportMode or str, optional
            ``Radiance`` (default) or ``Importance``.
        sample_flags : ReflTrans, optional
            Restrict sampling to these lobes (default ``ReflTrans.All``).
        out : SampleResult, optional
            A result of this call's shapes and dtypes to write into; it is returned.
        wavelengths : array_like, shape (..., 4), optional
            Spectral mode.
        normal : array_like, shape (..., 3), optional
            World-space shading normals, per element (broadcast with ``wo``): ``wo`` is then
            world-space, rotated into each element's frame before the model runs, and the
            sampled ``wi`` is returned in world space (``bsdfkit.models._frames``; float64
            arithmetic, rounded to wo's dtype). Unit within 1e-4 in ``|n|^2``.
        tangent : array_like, shape (..., 3), optional
            With ``normal``: the frame's x axis (anisotropic models), unit and perpendicular to
            the normal within 1e-4. Default: Duff et al. 2017's frame of the normal, Mitsuba 3's
            ``Frame3f(n)`` (the identity for n = (0, 0, 1)).
        uv : array_like, shape (..., 2), optional
            Texture coordinates, broadcast with the directions, for a model with textured
            parameters (``bsdfkit.textures``; required there); ignored by other models.
        duvdx, duvdy : array_like, shape (..., 2), optional
            With ``uv``: its screen-space derivatives, for filtered (MIP-mapped) lookups.

        Returns
        -------
        SampleResult
            ``wi``, ``f``, ``pdf``, ``flags``, ``eta``, ``valid``, ``pdf_is_proportional`` (and
            ``terminated`` in spectral mode), with the batch shape.

        Raises
        ------
        ValueError
            A direction that is not a finite unit vector, a uniform outside [0, 1] or NaN, both
            or neither of ``uc``/``u`` and ``n``, a negative seed; a bad ``normal`` or
            ``tangent`` (as ``eval``).
        TypeError
            An ``out`` that is not a SampleResult.

        Examples
        --------
        >>> import numpy as np, bsdfkit as bk
        >>> m = bk.Conductor.from_metal("Cu", alpha=0.2)
        >>> s = m.sample(bk.direction(np.radians(30), 0.0), n=4, seed=1)
        >>> s.wi.shape, s.f.shape, s.pdf.shape, bool(s.valid.all())
        ((4, 3), (4, 3), (4,), True)
        """
        if normal is not None or tangent is not None:   # world space: wi rotated back
            from . import _frames
            return _frames.sample(self, wo, uc, u, n, seed, mode, sample_flags, out, wavelengths, normal, tangent)
        if wavelengths is not None:
            return _spectral.sample(self, wo, uc, u, n, seed, wavelengths, mode, sample_flags, out)
        if out is not None:
            if type(out) is not SampleResult:
                raise TypeError(f"out: expected a SampleResult (e.g. an earlier result of sample), got {type(out).__name__}")
            out.__dict__.pop("_cos_wi", None)   # a world-space call's cosines (SampleResult.weight)
            return self._core.sample(wo, uc, u, mode, sample_flags, out, n, seed)
        return _sample_result(self._core.sample(wo, uc, u, mode, sample_flags, None, n, seed))

    def albedo(self, wo, n_samples: int = 65536, seed: int = 0, mode=TransportMode.Radiance, *,
               wavelengths=None, normal=None, tangent=None, uv=None, duvdx=None, duvdy=None) -> np.ndarray:
        """Directional albedo rho(wo) = integral of f |cos wi| dwi, per channel: shape (..., 3).

        Monte Carlo with ``n_samples`` importance samples per direction (pbrt-v4 ``rho``);
        deterministic for a given seed and independent of the thread count. The standard error
        falls as 1/sqrt(n_samples). ``wavelengths`` (..., 4), broadcast with wo: per wavelength,
        shape (..., 4) (a dispersive dielectric: each wavelength sampled as the hero).

        Parameters
        ----------
        wo : array_like, shape (..., 3)
            Unit outgoing directions in the local shading frame.
        n_samples : int, optional
            Importance samples per direction (default 65536).
        seed : int, optional
            Seed of the counter-based generator (default 0).
        mode : TransportMode or str, optional
            ``Radiance`` (default) or ``Importance``.
        wavelengths : array_like, shape (..., 4), optional
            Spectral mode: the albedo per wavelength.
        normal : array_like, shape (..., 3), optional
            World-space shading normals, per element (broadcast with ``wo``): ``wo`` is then
            world-space, rotated into each element's frame before the model runs
            (``bsdfkit.models._frames``; float64 arithmetic, rounded to wo's dtype). Unit within
            1e-4 in ``|n|^2``.
        tangent : array_like, shape (..., 3), optional
            With ``normal``: the frame's x axis (anisotropic models), unit and perpendicular to
            the normal within 1e-4. Default: Duff et al. 2017's frame of the normal, Mitsuba 3's
            ``Frame3f(n)`` (the identity for n = (0, 0, 1)).
        uv : array_like, shape (..., 2), optional
            Texture coordinates, broadcast with the directions, for a model with textured
            parameters (``bsdfkit.textures``; required there); ignored by other models.
        duvdx, duvdy : array_like, shape (..., 2), optional
            With ``uv``: its screen-space derivatives, for filtered (MIP-mapped) lookups.

        Returns
        -------
        numpy.ndarray, shape (..., 3)
            rho(wo) per RGB channel ((..., 4) per wavelength in spectral mode).

        Examples
        --------
        >>> import numpy as np, bsdfkit as bk
        >>> rho = bk.Diffuse([0.5, 0.5, 0.5]).albedo(bk.direction(np.radians(30), 0.0), n_samples=4096)
        >>> np.allclose(rho, 0.5, atol=0.02)
        True
        """
        if normal is not None or tangent is not None:
            from . import _frames
            return _frames.albedo(self, wo, n_samples, seed, mode, wavelengths, normal, tangent)
        if wavelengths is not None:
            return _spectral.albedo(self, wo, wavelengths, n_samples, seed, mode)
        return self._core.albedo(wo, n_samples, seed, mode)

    # ---- parameter gradients (bsdfkit.fitting; kept as one block)
    #: Fitting bounds of the differentiable parameters, name -> (lo, hi) (bsdfkit.fitting.fit).
    param_ranges: dict = {}

    def eval_grad(self, wo, wi, params=None, mode=TransportMode.Radiance, *, uv=None, duvdx=None, duvdy=None):
        """``(f, grad)``: f(wo, wi) (..., 3) and d f / d theta (..., 3, P), float64, from the
        model's own C++ code with forward-mode dual numbers. ``params``: names of the parameters
        (default: all differentiable ones); an RGB parameter gives three columns (``"eta"`` ->
        eta.r, eta.g, eta.b; ``"eta.g"`` one), ``"alpha"`` the isotropic alpha_x = alpha_y
        direction. Columns: ``bsdfkit.fitting.grad_columns``; one-sided and zero derivatives
        (smooth/rough switch, clamps, tables): ``bsdfkit.fitting.grad``. A bad name raises
        ValueError listing the differentiable parameters.

        Parameters
        ----------
        wo, wi : array_like, shape (..., 3)
            Unit directions in the local shading frame.
        params : sequence of str, optional
            Parameters to differentiate, in column order; default: all differentiable ones
            (``bsdfkit.fitting.differentiable_params``).
        mode : TransportMode or str, optional
            ``Radiance`` (default) or ``Importance``.

        Returns
        -------
        f : numpy.ndarray, shape (..., 3)
            The value, float64.
        grad : numpy.ndarray, shape (..., 3, P)
            d f / d theta, one column per entry of ``bsdfkit.fitting.grad_columns``.

        Raises
        ------
        ValueError
            An unknown or repeated parameter name; a direction that is not a finite unit vector.
        TypeError
            A model without a gradient kernel (the stochastic coated models, e.g.).

        Examples
        --------
        >>> import numpy as np, bsdfkit as bk
        >>> m = bk.Conductor.from_metal("Cu", alpha=0.2)
        >>> f, g = m.eval_grad(bk.direction(np.radians(30), 0.0), bk.direction(np.radians(30), np.pi))
        >>> f.shape, g.shape
        ((3,), (3, 8))
        """
        from ..fitting.grad import eval_grad
        return eval_grad(self, wo, wi, params, mode)


def _rebuild(cls, params):
    return cls._from_params(params)


def _pick_alpha(roughness, alpha):
    if roughness is not None and alpha is not None:
        raise ValueError("roughness, alpha: give one of them, not both")
    if roughness is not None:
        return roughness_to_alpha(_scalar(roughness, "roughness", lo=0.0, varying=True))
    return alpha


def core_value(v):
    """A parameter value as the compiled model's keyword takes it: a 1-D (RGB) array as a list, a
    per-element array as is (bind_varying.h), anything else unchanged."""
    if isinstance(v, np.ndarray) and v.ndim == 1 and v.size == 3:
        return v.tolist()
    return v
