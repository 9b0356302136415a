"""pbrt-v4 ``mix`` materials -> ``bk.Mix(..., method="stochastic")`` (pbrt-v4 MixMaterial: one of
the two named materials per shading point, the second with probability ``amount``); ``from_pbrt``
resolves them here once every other material of the scene is converted."""
from __future__ import annotations

import math

__all__ = ["resolve_mixes", "PBRT_MAX_MIX_DEPTH", "PBRT_MAX_MIX_LEAVES"]

_PARAMS = ("materials", "amount")

#: Deepest chain of mixes of mixes accepted (bk.Mix evaluates its children recursively: a chain
#: of a few hundred ran out of Python's recursion limit on the first eval).
PBRT_MAX_MIX_DEPTH = 64
#: Most materials a mix may expand to, each counted once per path to it (bk.Mix evaluates a
#: child once per path: 30 mixes that each name the next one twice are 2^30 evaluations per call,
#: a hang pbrt-v4 does not have as it picks one child per shading point).
PBRT_MAX_MIX_LEAVES = 1024


def _mix(rec, done, pending, fail, fail_param, float_param, stack, leaves):
    from ..models import Mix
    for p in rec.params.values():
        if p.name not in _PARAMS:
            fail_param(rec, p, "not a parameter of pbrt-v4's mix material; it takes " + ", ".join(_PARAMS))
    p = rec.params.get("materials")
    if p is None or p.type != "string" or len(p.values) != 2 or not all(isinstance(v, str) for v in p.values):
        fail(rec, 'expected "string materials" [ "a" "b" ] naming two materials (pbrt-v4 MixMaterial)')
    amount = float_param(rec, "amount", 0.5)
    if math.isnan(amount):
        fail_param(rec, rec.params["amount"], "is NaN")
    amount = min(max(amount, 0.0), 1.0)   # pbrt-v4 takes <= 0 as the first and >= 1 as the second material
    if len(stack) > PBRT_MAX_MIX_DEPTH:
        fail(rec, f"mixes of mixes nested deeper than {PBRT_MAX_MIX_DEPTH} ({' -> '.join(stack[:3])} -> ... -> "
             f"{stack[-1]}; bsdfkit.interop._pbrt_mix.PBRT_MAX_MIX_DEPTH)")
    kids = []
    for name in p.values:
        if name in stack:
            fail(rec, f"mix materials refer to each other in a cycle ({' -> '.join(stack + [name])})")
        if name not in done and name in pending:
            done[name] = _mix(pending[name], done, pending, fail, fail_param, float_param, stack + [name], leaves)
        if name not in done:
            fail(rec, f"material {name!r} of the mix is not defined or could not be converted")
        kids.append(done[name])
    n = leaves.get(p.values[0], 1) + leaves.get(p.values[1], 1)
    if n > PBRT_MAX_MIX_LEAVES:
        fail(rec, f"the mix expands to {n} materials counted once per path (more than {PBRT_MAX_MIX_LEAVES}: mixes "
             "that name the same material through several paths; bk.Mix evaluates each path, "
             "bsdfkit.interop._pbrt_mix.PBRT_MAX_MIX_LEAVES)")
    try:
        m = Mix(kids[0], kids[1], amount, method="stochastic")
    except (ValueError, TypeError) as e:
        fail(rec, str(e))
    leaves[rec.name] = n
    return m


def resolve_mixes(mixes, done, fail, fail_param, float_param, on_error):
    """Converts the ``mix`` records ``mixes`` (in file order) into ``done`` (name -> model), their
    children looked up there (mixes of mixes in any order); ``on_error(rec, error)`` handles a
    mix that cannot be converted (raise, or warn and skip)."""
    pending = {rec.name: rec for rec in mixes}
    leaves = {}   # mix name -> materials it expands to, counted per path
    for rec in mixes:
        if rec.name in done:
            continue
        try:
            done[rec.name] = _mix(rec, done, pending, fail, fail_param, float_param, [rec.name], leaves)
        except ValueError as e:
            on_error(rec, e)
