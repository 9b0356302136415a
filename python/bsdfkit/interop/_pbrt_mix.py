"""pbrt-v4 ``mix`` materials -> ``bk.Mix(..., method="stochastic")`` (pbrt-v4 MixMaterial: one of
the two named materials per shading point, the second with probability ``amount``); ``from_pbrt``
resolves them here once every other material of the scene is converted."""
from __future__ import annotations

__all__ = ["resolve_mixes"]

_PARAMS = ("materials", "amount")


def _mix(rec, done, pending, fail, fail_param, float_param, stack):
    from ..models import Mix
    for p in rec.params.values():
        if p.name not in _PARAMS:
            fail_param(rec, p, "not a parameter of pbrt-v4's mix material; it takes " + ", ".join(_PARAMS))
    p = rec.params.get("materials")
    if p is None or p.type != "string" or len(p.values) != 2:
        fail(rec, 'expected "string materials" [ "a" "b" ] naming two materials (pbrt-v4 MixMaterial)')
    amount = float_param(rec, "amount", 0.5)
    if not 0.0 <= amount <= 1.0:   # pbrt-v4 takes <= 0 as the first and >= 1 as the second material
        amount = min(max(amount, 0.0), 1.0)
    kids = []
    for name in p.values:
        if name in stack:
            fail(rec, f"mix materials refer to each other in a cycle ({' -> '.join(stack + [name])})")
        if name not in done and name in pending:
            done[name] = _mix(pending[name], done, pending, fail, fail_param, float_param, stack + [name])
        if name not in done:
            fail(rec, f"material {name!r} of the mix is not defined or could not be converted")
        kids.append(done[name])
    return Mix(kids[0], kids[1], amount, method="stochastic")


def resolve_mixes(mixes, done, fail, fail_param, float_param, on_error):
    """Converts the ``mix`` records ``mixes`` (in file order) into ``done`` (name -> model), their
    children looked up there (mixes of mixes in any order); ``on_error(rec, error)`` handles a
    mix that cannot be converted (raise, or warn and skip)."""
    pending = {rec.name: rec for rec in mixes}
    for rec in mixes:
        if rec.name in done:
            continue
        try:
            done[rec.name] = _mix(rec, done, pending, fail, fail_param, float_param, [rec.name])
        except ValueError as e:
            on_error(rec, e)
