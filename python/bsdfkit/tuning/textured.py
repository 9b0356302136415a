"""``simplify`` of a textured model (``bsdfkit.models.textured.Textured``): the cheapest knob
configuration within tol at every texel the material is measured at.

A textured material is one model per texel. Its error is measured over a set of texels, not at
one parameter value: ``n_texels`` uv points (a jittered stratified grid, deterministic for the
seed) are looked up, each gives a uniform model, and each is measured as :func:`simplify` measures
one model (the same direction set, errors against that texel's own model in float64). A
configuration of the material is a setting of its knobs; at a texel where a knob is moot (e.g. a
clear coat whose texture is 0 there), any setting of it is that texel's own configuration with the
knob moot. The material's error of a configuration is its *worst* texel's, so "within tol" holds at
every measured texel; among those, the cheapest is chosen exactly as :func:`simplify` ranks (the
shipped cost table). A lobe knob may drop a lobe whose parameter is a texture: the texture is then
replaced by the lobe's "off" value (the textures never needed it at the measured texels).
"""
from __future__ import annotations

import inspect
import warnings

import numpy as np

from .._progress import Progress
from .configs import _check_allow, _check_model, _specs, configurations
from .costs import _check_costs, _costs_for, _pick
from .errors import _Evaluation

__all__ = ["simplify_textured", "texel_uv"]


def texel_uv(n: int, seed: int = 0) -> np.ndarray:
    """``n`` uv points in [0, 1)^2: a jittered stratified grid (ceil(sqrt n) per axis, the first
    n cells in a seeded random order)."""
    rng = np.random.default_rng(seed)
    k = int(np.ceil(np.sqrt(n)))
    cells = rng.permutation(k * k)[:n]
    iu, iv = cells % k, cells // k
    return np.stack([(iu + rng.random(n)) / k, (iv + rng.random(n)) / k], -1)


def _match(ev, cfg):
    """The configuration of texel evaluation ``ev`` that is ``cfg`` there: equal labels where both
    are set, the texel's own (reference) label where ``cfg`` leaves a knob moot; None if absent."""
    ref = ev.reference.labels
    for i, c in enumerate(ev.configs):
        if c.dtype is not cfg.dtype:
            continue
        ok = True
        for k, lab in c.labels.items():
            want = cfg.labels.get(k)
            if lab is None:
                continue
            if want is None:
                want = ref.get(k)
            if lab != want:
                ok = False
                break
        if ok:
            return i
    return None


def simplify_textured(model, tol, metric, col, margin, directions, seed, n, n_albedo, allow, costs, progress,
                      n_texels):
    from .report import SimplifyReport, ToleranceNotMetWarning, _error_dict, _param_text, _same_value
    uv = texel_uv(n_texels, seed)
    texels = [model.at(p) for p in uv]
    for t in texels:
        _check_model(t)
    allowed = _check_allow(texels[0], allow)
    table = _check_costs(costs)
    # one bar over every texel's configurations (not one per texel)
    total = sum(len(configurations(t, allowed)) for t in texels)
    with Progress(progress, total, f"errors of configuration at {n_texels} texels", "simplify") as prog:
        evs = [_Evaluation(t, directions, n, seed, n_albedo, allow=allowed, reference="input", progress=prog,
                           what="simplify") for t in texels]
    # the base: the texel with the most reachable knobs (its configurations enumerate the material's)
    base = max(range(len(evs)), key=lambda j: (len(evs[j].configs), -j))
    bev = evs[base]
    errs, worst = [], []
    for c in bev.configs:
        e_all, w = None, None
        for j, ev in enumerate(evs):
            i = _match(ev, c)
            if i is None:
                e_all = None
                break
            e = ev.errors[i]
            if e_all is None or e[col] > e_all[col]:
                e_all, w = e, j
        errs.append(e_all)
        worst.append(w)
    valid = [i for i, e in enumerate(errs) if e is not None]
    ref_i = next(i for i, c in enumerate(bev.configs) if c is bev.reference)
    cands = [i for i in valid if errs[i][col] <= margin * tol] if tol > 0 else [ref_i]
    none_within = not cands
    if none_within:
        cands = [ref_i]
    cost = _costs_for(texels[base], bev.configs, table)
    best, ranked_by = _pick(cands, cost, bev.configs, [errs[i][col] if errs[i] is not None else np.inf
                                                       for i in range(len(errs))], bev.reference)
    cfg, err = bev.configs[best], errs[best]
    # the configuration applied to the textured material: the knobs' parameters the texel changed
    names = inspect.signature(model.model_class).parameters
    knob_of = {s.param: s for s in _specs(texels[base], allowed) if s.param is not None}
    new = dict(model._params)
    changes = []
    for k, s in knob_of.items():
        before, after = texels[base]._params.get(k), cfg.model._params.get(k)
        if _same_value(before, after):
            continue
        if k not in names:
            raise NotImplementedError(f"simplify: {model.model_class.__name__}'s knob parameter {k!r} is not a "
                                      "constructor argument; cannot apply it to the textured material")
        was = model._params.get(k, before)
        new[k] = after
        why = f"worst of {n_texels} texels: {metric} error {err[col]:.2e} <= {margin:g} tol"
        if s.lobe:
            why += "; the lobe is dropped" + (" (its texture is not needed)" if hasattr(was, "lookup") else "")
        changes.append((k, repr(was) if hasattr(was, "lookup") else _param_text(was), _param_text(after), why))
    if cfg.dtype is np.float32:
        changes.append(("precision", "float64", "float32", f"worst of {n_texels} texels within tol"))
    out = model.model_class(**new)
    ref_cost = cost[0]
    exp = None if cost[best] is None or ref_cost is None else ref_cost / cost[best]
    vs_in = None if cost[ref_i] is None or cost[best] is None else cost[ref_i] / cost[best]
    notes = [f"measured at {n_texels} texels (uv on a jittered grid, seed {seed}); errors are the worst texel's "
             f"(texel {worst[best]} at uv {np.round(uv[worst[best]], 4).tolist()})"]
    if none_within:
        notes.append(f"no configuration has {metric} error <= {margin:g} tol at every texel; the input is returned")
    report = SimplifyReport(
        input_model=model, model=out, dtype=cfg.dtype, config=dict(cfg.labels), changes=changes, kept=[],
        error=_error_dict(err, bev.stochastic or metric == "rms", bev.stochastic), tol=tol, metric=metric,
        expected_speedup=exp, speedup_vs_input=vs_in, ranked_by=ranked_by, reference=model,
        description=cfg.describe(), n_configurations=len(valid), n_within_tol=0 if none_within else len(cands),
        seed=seed, floor=min(ev.floor for ev in evs), notes=notes,
        fixed=[(d.name, _param_text(texels[base]._params[d.keyword])) for d in type(texels[base]).knobs
               if d.kind == "modelling" and d.name not in allowed],
        allow=tuple(sorted(allowed)), within_tol=bool(err[col] <= tol))
    if not report.within_tol:
        warnings.warn(f"simplify: tolerance not met: no configuration of {model.describe()} has {metric} error "
                      f"<= {tol:g} at every texel; the input is returned (report.within_tol is False)",
                      ToleranceNotMetWarning, stacklevel=3)
    return out, report
