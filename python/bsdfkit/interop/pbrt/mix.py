"""pbrt-v4 ``mix`` materials -> ``bk.Mix(..., method="stochastic")`` (pbrt-v4 MixMaterial: one of
the two named materials per shading point, the second with probability ``amount``); ``from_pbrt``
resolves them here once every other material of the scene is converted."""
from __future__ import annotations

import math

from ...textures import TextureBase
from .textures import PbrtLookup

__all__ = ["resolve_mixes", "PBRT_MAX_MIX_DEPTH", "PBRT_MAX_MIX_LEAVES"]

_PARAMS = ("materials", "amount")

#: Most levels of mixes of mixes accepted (bk.Mix evaluates its children recursively: a chain of
#: a few hundred ran out of Python's recursion limit on the first eval).
PBRT_MAX_MIX_DEPTH = 64
#: Most materials a mix may expand to, each counted once per path to it (bk.Mix evaluates a
#: child once per path: 30 mixes that each name the next one twice are 2^30 evaluations per call,
#: a hang pbrt-v4 does not have as it picks one child per shading point).
PBRT_MAX_MIX_LEAVES = 1024


def _check(rec, fail, fail_param, float_param):
    """(the two material names, amount) of a mix record, or the error naming its parameter."""
    for p in rec.params.values():
        if p.name not in _PARAMS:
            fail_param(rec, p, "not a parameter of pbrt-v4's mix material; it takes " + ", ".join(_PARAMS))
    p = rec.params.get("materials")
    if p is None or p.type != "string" or len(p.values) != 2 or not all(isinstance(v, str) for v in p.values):
        fail(rec, 'expected "string materials" [ "a" "b" ] naming two materials (pbrt-v4 MixMaterial)')
    amount = float_param(rec, "amount", 0.5)
    if isinstance(amount, TextureBase):   # a float texture: clamped per lookup
        return tuple(p.values), PbrtLookup("clamp01", amount)
    if math.isnan(amount):
        fail_param(rec, rec.params["amount"], "is NaN")
    # pbrt-v4 MixMaterial::ChooseMaterial takes <= 0 as the first and >= 1 as the second material
    return tuple(p.values), min(max(amount, 0.0), 1.0)


def resolve_mixes(mixes, done, fail, fail_param, float_param, on_error):
    """Converts the ``mix`` records ``mixes`` (in file order) into ``done`` (name -> model), their
    children looked up there (mixes of mixes in any order); ``on_error(rec, error)`` handles a
    mix that cannot be converted (raise, or warn and skip). Children first, without recursion
    (an explicit depth-first stack), each mix once: linear in the number of mixes."""
    from ...models import Mix

    pending = {rec.name: rec for rec in mixes}
    height, leaves, failed = {}, {}, {}   # per mix: levels of mixes, materials per path; errors
    cause = {}                            # per mix failed through a child: the innermost error

    def build(rec, names, amount):
        for name in names:
            if name in failed:   # the innermost reason, once (not nested per level)
                cause[rec.name] = cause.get(name, str(failed[name]))
                fail(rec, f"material {name!r} of the mix could not be converted: {cause[rec.name]}")
            if name not in done:
                fail(rec, f"material {name!r} of the mix is not defined or could not be converted")
        h = 1 + max(height.get(n, 0) for n in names)
        if h > PBRT_MAX_MIX_DEPTH:
            fail(rec, f"mixes of mixes nested {h} deep (more than {PBRT_MAX_MIX_DEPTH}; "
                 "bsdfkit.interop.pbrt.mix.PBRT_MAX_MIX_DEPTH)")
        n = leaves.get(names[0], 1) + leaves.get(names[1], 1)
        if n > PBRT_MAX_MIX_LEAVES:
            fail(rec, f"the mix expands to {n} materials counted once per path (more than {PBRT_MAX_MIX_LEAVES}: "
                 "mixes that name the same material through several paths; bk.Mix evaluates each path, "
                 "bsdfkit.interop.pbrt.mix.PBRT_MAX_MIX_LEAVES)")
        try:
            m = Mix(done[names[0]], done[names[1]], amount, method="stochastic")
        except (ValueError, TypeError) as e:
            fail(rec, str(e))
        height[rec.name], leaves[rec.name] = h, n
        return m

    for root in mixes:
        stack, gray, args = [(root.name, False)], set(), {}
        while stack:
            name, children_done = stack.pop()
            rec = pending[name]
            try:
                if name in done or name in failed:
                    continue
                if not children_done:
                    args[name] = _check(rec, fail, fail_param, float_param)
                    gray.add(name)
                    stack.append((name, True))
                    for child in args[name][0]:
                        if child in gray:
                            path = [n for n, c in stack if c and n in gray]
                            fail(rec, "mix materials refer to each other in a cycle ("
                                 + " -> ".join(path[path.index(child):] + [child]) + ")")
                        if child in pending and child not in done and child not in failed:
                            stack.append((child, False))
                else:
                    gray.discard(name)
                    done[name] = build(rec, *args[name])
            except ValueError as e:
                failed[name] = e
                gray.discard(name)
                stack = [(n, c) for n, c in stack if n != name]
        if root.name in failed:
            on_error(root, failed[root.name])
