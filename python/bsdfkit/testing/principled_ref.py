"""Mitsuba 3's ``principled`` and ``principledthin`` plugins as the reference of
:class:`bsdfkit.Principled` and :class:`bsdfkit.PrincipledThin`, in bsdfkit / pbrt-v4 conventions.

Everything goes through :mod:`bsdfkit.testing.mitsuba` (the naming swap ``wo`` <-> Mitsuba's
``si.wi``, the cosine removed, float32 inputs, ``llvm_ad_rgb``); this module adds the plugin
dictionaries written from a parameter dict (not from the models' ``to_mitsuba``, so that the
export is checked too) and the plugins' known differences from bsdfkit's conventions:

* **Black from below.** With no transmission (``spec_trans`` 0 or ``metallic`` 1) Mitsuba's
  ``principled`` returns f = 0 for ``wo`` below the surface but a nonzero pdf (its specular lobe's
  density; its sampler returns no sample there). bsdfkit returns f = pdf = 0 there:
  :func:`comparable` masks those pairs out.
* **Sheen without a diffuse lobe.** Mitsuba's ``principled`` evaluates the sheen inside
  ``if (any(diffuse_active))``: in ``scalar_rgb`` the sheen vanishes where the diffuse weight
  (1 - metallic)(1 - spec_trans) is 0 (spec_trans = 1), in the JIT variants (where ``any_or<true>``
  is true) it does not. bsdfkit follows the mask formula, i.e. the JIT variants (the default here).
* **Flags.** ``principledthin`` always declares a glossy reflection lobe; bsdfkit declares it only
  when ``spec_trans`` > 0 (the lobe's weight).
* **Precision.** Mitsuba's wheels are float32. The smooth reflection lobes agree with a float64
  bsdfkit to ~5e-7 .. 8e-6 relative (p99.9); the rough transmission of ``principled`` is
  ill-conditioned in float32 (the half vector wo + eta wi, the Fresnel transmittance near total
  internal reflection, the GGX tail), and so are near-delta lobes (alpha 0.01) and the Fresnel
  reflection near eta = 1: there float32 rounding alone (bsdfkit's own float32 kernels included)
  moves values by up to ~7e-3 relative at p99.9, and the tests compare against that rounding
  (tests/models/test_principled.py).
"""
from __future__ import annotations

import numpy as np

from . import mitsuba as _mi

__all__ = ["mitsuba_dict", "eval_pdf", "comparable", "PRINCIPLED_COLOURS"]

#: The parameters that are colours (a Mitsuba ``rgb`` value); every other one is a float.
PRINCIPLED_COLOURS = ("base_color",)


def mitsuba_dict(params: dict, thin: bool = False) -> dict:
    """The Mitsuba plugin dictionary of ``principled`` (``principledthin`` if ``thin``) with the
    given parameters, by Mitsuba's names (``eta`` or ``specular``; colours as 1 or 3 numbers)."""
    d = {"type": "principledthin" if thin else "principled"}
    for k, v in params.items():
        if k in PRINCIPLED_COLOURS:
            d[k] = {"type": "rgb", "value": [float(x) for x in np.broadcast_to(np.asarray(v, float), (3,))]}
        else:
            d[k] = float(v)
    return d


def eval_pdf(params: dict, wo, wi, mode="radiance", thin: bool = False):
    """Mitsuba's f (cosine excluded) and pdf of the plugin with these parameters at bsdfkit's
    ``wo`` (towards the viewer) and ``wi``: ``(f (..., 3), pdf (...))`` as float64."""
    return _mi.eval_pdf(mitsuba_dict(params, thin), wo, wi, mode)


def comparable(params: dict, wo, thin: bool = False) -> np.ndarray:
    """Where bsdfkit and Mitsuba follow the same conventions: everywhere for ``principledthin``,
    and for ``principled`` wherever ``wo`` is above the surface or the material transmits
    (``spec_trans`` > 0 and ``metallic`` < 1); see the module notes."""
    wo = np.asarray(wo, dtype=np.float64)
    if thin:
        return np.ones(wo.shape[:-1], bool)
    st, met = float(params.get("spec_trans", 0.0)), float(params.get("metallic", 0.0))
    transmits = st > 0 and (1 - met) * st > 0
    return np.ones(wo.shape[:-1], bool) if transmits else wo[..., 2] > 0
