"""Forward-mode automatic differentiation of the Dr.Jit float64 references (``drjit_models``),
the oracle of ``eval_grad``'s tests.

``reference_grad(fn, columns, *args, **kwargs)`` calls a reference function of
``bsdfkit.testing.drjit_models`` on Dr.Jit's AD backend (``drjit.llvm.ad.Float64``) with
gradients enabled on the parameters its ``_prep`` converts, and propagates each column with
``dr.forward_to``. A column is a list of parameter slots seeded together: ``("s", i)`` is the
i-th scalar argument of the reference's ``_prep``, ``("c", i, ch)`` channel ch of its i-th
spectrum argument (e.g. ``conductor_f``: scalars (ax, ay), spectra (eta, k)). Returns
``(values, grads)``: the reference's outputs (as it returns them) and, per output, an array of
its shape plus a trailing axis of len(columns).
"""
from __future__ import annotations

import numpy as np

from . import _drjit_backend
from . import drjit_models as _dm

__all__ = ["reference_grad", "standard_grad", "cloth_grad", "coated_analytic_grad", "plastic_grad"]


class _Tracer:
    def __init__(self, columns):
        import drjit.llvm.ad as ad
        self.Float64 = ad.Float64
        self.columns = columns
        self.grads = []
        self.vars = None

    def prep(self, fs, cs):
        dr, _ = _drjit_backend()
        slots = {}
        for col in self.columns:
            for s in col:
                key = tuple(s)
                if key in slots:
                    continue
                v = fs[s[1]] if s[0] == "s" else cs[s[1]][s[2]]
                dr.enable_grad(v)
                slots[key] = v
        self.vars = slots

    def out(self, batch, arrs, rgb):
        dr, _ = _drjit_backend()
        per_col = []
        for col in self.columns:
            for v in self.vars.values():
                dr.set_grad(v, 0.0)
            for a in arrs:
                dr.clear_grad(a)
            for s in col:
                dr.set_grad(self.vars[tuple(s)], 1.0)
            dr.forward_to(*arrs, flags=dr.ADFlag.ClearInterior | dr.ADFlag.AllowNoGrad)
            per_col.append([np.asarray(dr.grad(a).numpy(), dtype=np.float64).reshape(batch) for a in arrs])
        g = [np.stack([pc[k] for pc in per_col], axis=-1) for k in range(len(arrs))]  # each batch + (P,)
        if rgb:  # the three channels of one output: batch + (3, P)
            self.grads.append(np.stack(g, axis=-2))
        else:
            self.grads.extend(g)


def reference_grad(fn, columns, *args, **kwargs):
    """(values, grads) of the reference ``fn`` (see the module docstring): grads has one array
    per output of ``fn`` (a tuple when ``fn`` returns a tuple), of the output's shape + (P,)."""
    if _dm._TRACE is not None:
        raise RuntimeError("reference_grad: not re-entrant")
    tr = _Tracer([list(map(tuple, c)) for c in columns])
    _dm._TRACE = tr
    try:
        vals = fn(*args, **kwargs)
    finally:
        _dm._TRACE = None
    if isinstance(vals, (tuple, list)):
        vals = tuple(vals)
        if len(tr.grads) != len(vals):
            raise RuntimeError(f"reference_grad: {len(vals)} outputs but {len(tr.grads)} gradients")
        return vals, tuple(tr.grads)
    if len(tr.grads) != 1:
        raise RuntimeError(f"reference_grad: expected one output, got {len(tr.grads)} gradients")
    return vals, tr.grads[0]


def _namespace_grad(model, columns, call):
    """(f, grad (..., 3, P)) of ``call(namespace)``, a reference reading its parameters from a
    namespace of ``model``'s parameters, with every (field, channel) of ``columns`` a Dr.Jit AD
    leaf (channel -1: a scalar field); derivatives propagate by forward-mode AD."""
    import types

    import drjit.llvm.ad as ad
    dr, _ = _drjit_backend()
    if _dm._TRACE is not None:
        raise RuntimeError("reference grad: not re-entrant")
    columns = [[tuple(s) for s in c] for c in columns]
    ns = dict(model._params)
    leaves = {}
    for col in columns:
        for field, ch in col:
            if field not in ns:
                raise ValueError(f"reference grad: no parameter {field!r}")
            if ch == -1:
                if (field, -1) not in leaves:
                    v = ad.Float64(float(ns[field]))
                    dr.enable_grad(v)
                    ns[field] = leaves[(field, -1)] = v
            else:
                if not isinstance(ns[field], list):
                    ns[field] = [ad.Float64(float(x)) for x in np.broadcast_to(np.asarray(ns[field], float), (3,))]
                if (field, ch) not in leaves:
                    dr.enable_grad(ns[field][ch])
                    leaves[(field, ch)] = ns[field][ch]
    tr = _Tracer(columns)
    tr.vars = leaves
    _dm._TRACE = tr
    try:
        f = call(types.SimpleNamespace(**ns))
    finally:
        _dm._TRACE = None
    return f, tr.grads[0]


def standard_grad(model, wo, wi, lut, columns):
    """(f, grad) of the Filament reference ``drjit_filament.standard_f`` with forward-mode AD on
    the parameters of ``model`` (a ``FilamentStandard``): each column is a list of
    ``(field, channel)`` pairs seeded together (channel -1 for a scalar field), as
    ``eval_grad``'s columns (``bsdfkit.fitting.grad._columns``). The derived parameters
    (f0, f90, roughness clamps, anisotropic alphas, the DFG rows' weights) are computed with
    Dr.Jit from the seeded leaves, so the derivative goes through them. grad: (..., 3, P)."""
    from . import drjit_filament as djf
    return _namespace_grad(model, columns, lambda ns: djf.standard_f(ns, wo, wi, lut))


def cloth_grad(model, wo, wi, columns):
    """(f, grad) of ``drjit_filament.cloth_f`` with forward-mode AD on the parameters of ``model``
    (a ``FilamentCloth`` with an explicit sheen_color: the derivative of base_color does not
    include the default sheen_color = sqrt(base_color)), columns as ``standard_grad``."""
    from . import drjit_filament as djf
    if model.sheen_color is None:
        raise ValueError("cloth_grad: give the model an explicit sheen_color")
    return _namespace_grad(model, columns, lambda ns: djf.cloth_f(ns, wo, wi))


def coated_analytic_grad(model, wo, wi, columns):
    """(f, grad) of ``layered_analytic_ref.coated_f`` (the analytic layered approximation restated
    from its formulas) with forward-mode AD on the parameters of ``model`` (a ``CoatedDiffuse`` or
    ``CoatedConductor`` with method="analytic"), columns as ``standard_grad``."""
    from . import layered_analytic_ref as lar
    return _namespace_grad(model, columns, lambda ns: lar.coated_f(ns, type(model).__name__, wo, wi))


def plastic_grad(model, wo, wi, columns):
    """(f, grad) of ``plastic_ref.plastic_f`` (Plastic restated from its formulas, the rough
    coat's tables computed from the seeded alpha and eta) with forward-mode AD on the parameters
    of ``model`` (a ``Plastic``), columns as ``standard_grad``."""
    from . import plastic_ref as pr
    return _namespace_grad(model, columns, lambda ns: pr.plastic_f(ns, wo, wi))
