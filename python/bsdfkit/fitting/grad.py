"""Parameter gradients of the models: ``eval_grad``.

The derivatives come from the models' own C++ code instantiated with a forward-mode dual number
as its float type (``cpp/include/bsdfkit/core/dual.h``), not from a second, hand-differentiated
copy: the model is rebuilt from dual-valued parameters, so d f / d theta flows through each
model's parameter preprocessing (the conductor's Schlick F0 / F82 terms, Filament's f0, roughness
remapping and DFG rows).

Gradient columns. ``params`` names the parameters to differentiate, in order; a scalar parameter
is one column, an RGB parameter three (``"eta"`` -> ``eta.r, eta.g, eta.b``), and one channel
can be named alone (``"eta.g"``). Microfacet models with ``alpha_x`` / ``alpha_y`` also accept
``"alpha"``: the derivative along alpha_x = alpha_y (d/dt f(alpha_x + t, alpha_y + t)), which is
the derivative with respect to the isotropic alpha (likewise ``"conductor_alpha"`` and
``"interface_alpha"`` of CoatedConductor). :func:`grad_columns` lists the columns.

Each field is differentiated on its own: a parameter whose default is derived from another
(FilamentCloth's sheen_color = sqrt(base_color) when None) is held at its value.

Where the derivative is one-sided or zero (see core/dual.h): the smooth/rough switch
(max(alpha) < 1e-3: the delta lobe evaluates to 0, and so does its derivative; at and above
1e-3 the rough lobe's derivative), clamps and selects (the derivative of the branch taken; 0
where a bound is active, e.g. Filament's roughness clamp at its minimum, f90 = saturate(...) at
1, the alpha floor 1e-4), and Filament's DFG table (the derivative of the bilinear
interpolant along roughness).

Per family: FilamentCloth's roughness is clamped to [min perceptual roughness, 1] (0 beyond,
one-sided at the ends); the analytic coated models (CoatedDiffuse / CoatedConductor with
method="analytic") floor the thickness at FLT_MIN and clamp g to [-0.99, 0.99] (0 beyond), and
their internal-reflection sum M is differentiated through its 64-node quadratures (the derivative
of the model as computed, not of the exact integral); beyond the coat's critical angle (eta < 1)
the refracted cosine is 0, the absorption term and its derivative are 0. The stochastic coated
models have no gradient kernel (each eval is a random walk). Plastic: below alpha = 1e-3 the
coat is smooth (its delta lobe evaluates to 0; f does not depend on alpha, whose derivative is
0), from 1e-3 on the rough coat's derivative (f jumps at the switch: T = 1 - F and Mitsuba's
fitted Fdr become the tabulated T and the quadrature's Fdr). The rough coat's transmittance
table and Fdr are differentiated through their Gauss-Legendre rules (the derivative of the rule
as computed, per node, in alpha and eta); T(cos) is the linear interpolant of the table, so
d f / d theta interpolates the nodes' derivatives. The rule's integrands have kinks (the
critical angle of the internal reflectance, whose derivative is a square-root singularity, and
the horizon test), so the tables are continuous in alpha and eta but their derivatives vary
sharply wherever a node crosses one: the derivative returned is exact between such crossings,
and central differences agree with it only for steps below the node spacing (e.g. d Fdr /
d alpha at alpha 0.2, eta 1.49: -0.6334 exact, -0.6333 for h = 1e-7, -0.654 for h = 1e-6).
"""
from __future__ import annotations

import numpy as np

from .._arrays import as_dirs, broadcast_batch, flatten_to
from .._enums import TransportMode

__all__ = ["eval_grad", "grad_columns", "differentiable_params"]

_CHANNELS = ("r", "g", "b")


def _core_fields(core) -> dict:
    fields = getattr(core, "grad_fields", None)
    if fields is None:
        return {}
    return {name: int(n) for name, n in fields}


def _supported(model) -> bool:
    return hasattr(model._core, "eval_grad")


def differentiable_params(model) -> tuple:
    """Names ``eval_grad`` accepts for ``model`` (RGB parameters as one name; ``"alpha"`` where
    the model has alpha_x and alpha_y). Empty for a model without a gradient kernel.

    Parameters
    ----------
    model : BxDF
        Any model.

    Returns
    -------
    tuple of str
        The parameter names, in the model's field order.

    Examples
    --------
    >>> import bsdfkit as bk
    >>> bk.fitting.differentiable_params(bk.Conductor.from_metal("Cu", alpha=0.2))
    ('eta', 'k', 'alpha', 'alpha_x', 'alpha_y')
    """
    if not _supported(model):
        return ()
    fields = _core_fields(model._core)
    names = list(fields)
    for iso in _iso_alphas(fields):
        names.insert(names.index(iso + "_x"), iso)
    return tuple(names)


def _iso_alphas(fields) -> list:
    """The isotropic alpha names of a model's fields: "alpha" for alpha_x / alpha_y, and
    "<prefix>alpha" for <prefix>alpha_x / <prefix>alpha_y (e.g. CoatedConductor's
    "conductor_alpha", "interface_alpha")."""
    return [f[:-2] for f in fields if f.endswith("alpha_x") and f[:-2] + "_y" in fields]


def _columns(model, params):
    """([column names], [column seeds]) for ``params`` (None = every differentiable field)."""
    if not _supported(model):
        from .. import _core
        from ..models.registry import classes
        ok = [c.__name__ for c in classes() if hasattr(getattr(_core, c.__name__, None), "eval_grad")]
        raise TypeError(f"eval_grad: {type(model).__name__} has no gradient kernel"
                        + (f" (models with one: {', '.join(ok)})" if ok else ""))
    fields = _core_fields(model._core)
    if params is None:
        params = tuple(fields)
    elif isinstance(params, str):
        params = (params,)
    else:
        try:
            params = tuple(params)
        except TypeError:
            raise TypeError(f"params: expected a sequence of parameter names, got {type(params).__name__}") from None
    if not params:
        raise ValueError("params: name at least one parameter to differentiate")
    names, cols = [], []
    for p in params:
        if not isinstance(p, str):
            raise TypeError(f"params: expected parameter names (str), got {type(p).__name__}")
        base, _, ch = p.partition(".")
        if p in _iso_alphas(fields):
            names.append(p)
            cols.append([(p + "_x", -1), (p + "_y", -1)])
        elif base in fields and fields[base] == 3 and ch == "":
            for c, cn in enumerate(_CHANNELS):
                names.append(f"{base}.{cn}")
                cols.append([(base, c)])
        elif base in fields and fields[base] == 3 and ch in _CHANNELS:
            names.append(p)
            cols.append([(base, _CHANNELS.index(ch))])
        elif p in fields and fields[p] == 1:
            names.append(p)
            cols.append([(p, -1)])
        else:
            raise ValueError(f"params: {p!r} is not a differentiable parameter of {type(model).__name__}; "
                             f"differentiable: {', '.join(differentiable_params(model))} "
                             "(RGB ones also per channel, e.g. 'name.r')")
    if len(set(names)) != len(names):
        raise ValueError(f"params: a parameter is named twice ({', '.join(names)})")
    limit = int(model._core.grad_max_columns)
    if len(cols) > limit:
        raise ValueError(f"params: at most {limit} gradient columns for {type(model).__name__}, got {len(cols)}")
    return names, cols


def grad_columns(model, params=None) -> tuple:
    """The gradient columns of ``eval_grad(..., params=params)``, e.g. ``("eta.r", "eta.g",
    "eta.b", "alpha")``.

    Parameters
    ----------
    model : BxDF
        A model with a gradient kernel.
    params : str or sequence of str, optional
        As ``eval_grad``'s; default: every differentiable field.

    Returns
    -------
    tuple of str
        One name per column of the gradient.

    Raises
    ------
    ValueError
        An unknown or repeated name, or more columns than the kernel supports.
    TypeError
        A model without a gradient kernel.

    Examples
    --------
    >>> import bsdfkit as bk
    >>> bk.fitting.grad_columns(bk.Conductor.from_metal("Cu", alpha=0.2), ["eta", "alpha"])
    ('eta.r', 'eta.g', 'eta.b', 'alpha')
    """
    return tuple(_columns(model, params)[0])


def eval_grad(model, wo, wi, params=None, mode=TransportMode.Radiance):
    """``(f, grad)``: f(wo, wi) (..., 3) and its derivatives (..., 3, P) with respect to the
    columns of ``params`` (see :func:`grad_columns`), in float64 (float32 directions are
    evaluated in float64 too). Inputs as ``model.eval``; ``model.eval_grad`` calls this.

    Parameters
    ----------
    model : BxDF
        A model with a gradient kernel.
    wo, wi : array_like, shape (..., 3)
        Unit directions in the local shading frame.
    params : str or sequence of str, optional
        The parameters to differentiate (see :func:`grad_columns`); default: all.
    mode : TransportMode or str, optional
        ``Radiance`` (default) or ``Importance``.

    Returns
    -------
    f : numpy.ndarray, shape (..., 3)
        The value, float64.
    grad : numpy.ndarray, shape (..., 3, P)
        The derivatives, one column per gradient column.

    Raises
    ------
    ValueError
        A bad parameter name (see :func:`grad_columns`) or direction.
    TypeError
        A model without a gradient kernel.

    Examples
    --------
    >>> import numpy as np, bsdfkit as bk
    >>> m = bk.Diffuse([0.5, 0.5, 0.5])
    >>> f, g = bk.fitting.eval_grad(m, bk.direction(0.3, 0.0), bk.direction(0.5, 1.0), ["reflectance.r"])
    >>> bool(np.isclose(g[0, 0], 1 / np.pi))   # f = R / pi
    True
    """
    from .._validate import check_mode as _mode, raise_bad as _raise_bad
    core = model._grad_core(params) if hasattr(model, "_grad_core") else model._core
    names, cols = _columns(model, params)
    wo, wi = as_dirs(wo, "wo"), as_dirs(wi, "wi")
    # per-element parameters broadcast with the directions (their shapes from the compiled model)
    vs = tuple(getattr(core, "varying_shapes", ()))
    batch = broadcast_batch(("wo", "wi") + tuple(n for n, _ in vs), wo.shape[:-1], wi.shape[:-1],
                            *(tuple(s) for _, s in vs))
    P = len(cols)
    f = np.empty(batch + (3,))
    g = np.empty(batch + (3, P))
    if f.size:
        if vs:   # full rows of the batch, which the compiled call takes with the batch shape
            wo, wi = np.broadcast_to(wo, batch + (3,)), np.broadcast_to(wi, batch + (3,))
        bo, bi = core.eval_grad(flatten_to(wo, batch, (3,), np.float64), flatten_to(wi, batch, (3,), np.float64),
                                _mode(mode), cols, f.reshape(-1, 3), g.reshape(-1, 3, P), *((batch,) if vs else ()))
        _raise_bad("wo", bo)
        _raise_bad("wi", bi)
    return f, g
