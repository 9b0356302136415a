"""Speed versus accuracy: knobs, errors, costs and the reports :func:`tradeoff` and :func:`simplify`.

Modules: ``configs`` (the knobs of each model and the configurations they span), ``errors`` (direction
sets, relative error against a reference), ``costs`` (the shipped cost table, live timing), ``report``
(:class:`Table`, :func:`tradeoff`, :class:`SimplifyReport`, :func:`simplify`). The plot of a table is
:func:`bsdfkit.plot.pareto`.

Every approximation in bsdfkit is a *knob* of a model: one code path with the setting as a
parameter, never a copied model variant. :func:`knobs` lists the knobs of a model instance,
each with its settings ordered from the most accurate to the cheapest:

===================  ==============================================  =====================================
model                knob (most accurate -> cheapest)                 moot (not an accuracy choice) when
===================  ==============================================  =====================================
every model          precision: float64 -> float32                    never (a property of the call: float32
                                                                      directions run float32 kernels)
Conductor            fresnel: exact -> f82 -> schlick                 never
                     masking: correlated -> separable                 smooth (max alpha < 1e-3: a mirror)
Dielectric           masking: correlated -> separable                 smooth, or eta == 1
FilamentStandard     clear_coat (lobe): keep -> drop (0)              clear_coat == 0
                     sheen (lobe): keep -> drop (sheen_color 0)       sheen_color == 0
                     diffuse: burley -> lambert                       no diffuse colour (metallic 1 / black)
                     visibility: correlated -> fast                   anisotropy != 0 (always anisotropic V)
                     f90: filament -> one                             16.5 sum(f0) >= 1 (the rule gives 1)
                     energy_compensation: True -> False               f0 == 0
                     dfg_lut_size: 128 -> 64 -> 32 -> 16              energy compensation off and no sheen
FilamentCloth        diffuse: burley -> lambert                       black base colour
                     dfg_lut_size                                     always: only lobe selection uses it
===================  ==============================================  =====================================

Why these orders: Lambert is Burley's diffuse with its retro-reflection / grazing term switched
off (``Fd_Burley`` with f90 = 1 *is* ``Fd_Lambert``), so Burley, which reproduces the roughness-
dependent diffuse falloff Burley 2012 fitted to measured (MERL) materials, is treated as the more
accurate one, although Filament defaults to Lambert. ``f90 = 1`` is the "filament" rule without
its specular-occlusion clamp for f0 below 2 %; energy compensation off drops the multiple-
scattering term; smaller DFG tables interpolate coarser. Knobs that change *which* material is
modelled rather than how accurately (``min_roughness``, ``clear_coat_layering``,
``clear_coat_ior_change``, Filament cloth's ``subsurface_color``, every physical parameter) are not
knobs here: the user's value is kept. The cloth's DFG table only feeds the lobe-selection
probabilities of ``sample``/``pdf`` (sampling efficiency, not f or the albedo), so it is never an
accuracy knob. Lobe knobs drop a lobe (strength 0): the model then also gets the compiled variant
without that lobe. A knob is *reachable* in a configuration unless it is moot there; a moot knob
keeps the user's value and configurations that differ only in moot knobs are one configuration.

Error definition (used by :func:`tradeoff`, :func:`simplify`, the tests and ``bench/tradeoff.py``):

* values compared: ``v = f(wo, wi) |cos theta_i|`` per direction pair and RGB channel, the cosine
  of the float64 ``wi``; a float32 configuration is run on float32 copies of the directions
  (and uniforms), because precision is a property of the call in bsdfkit.
* relative error per pair and channel: ``|v_cfg - v_ref| / max(|v_ref|, floor)`` with
  ``floor = 1e-3 * mean(albedo_ref) / pi``: relative where the reference is brighter than a
  thousandth of a Lambertian surface of the material's mean directional albedo, absolute in those
  units below it. A floor taken from the set itself (``1e-3 max|v_ref|``) would be set by the
  highlight peak of a glossy lobe (1e4 and more for alpha ~ 0.01) and hide every error off the
  peak; this one depends only on how much light the material reflects, not on how peaked it is
  nor on how the direction set was drawn. ``Table.floor`` holds the value used.
* ``max_err`` and ``p99_err``: the maximum and numpy's default (linear) 0.99-quantile of that
  relative error over every pair and channel of the direction set.
* ``albedo_err``: ``max |albedo_cfg(wo) - albedo_ref(wo)|`` over channels and the albedo set of
  wo (cos theta_o = 1, 0.7, 0.4, 0.15, 0.05, 0.01, also below the surface for transmissive
  models). Both albedos are estimated from the *same* importance samples of the reference
  configuration (``f_cfg |cos| / pdf_ref``; stratified uniforms, common to all configurations), so
  their difference is estimated with an error proportional to the difference itself, far below
  the tolerances (an independent Monte Carlo estimate per configuration would need ~1e8 samples
  for 1e-4). A stochastic reference (CoatedDiffuse, CoatedConductor: ``sample`` returns a pdf
  only proportional to the density, ``pdf_is_proportional``) cannot weight by ``1 / pdf_ref``:
  then each configuration's albedo is the mean of its *own* sampling weights ``f |cos| / pdf``
  (exact in expectation; pbrt-v4's ``rho``) over the same uniforms, 4096 per wo by default, and
  ``albedo_err`` includes that Monte Carlo noise (~1e-3 for an albedo ~0.5).
* delta (specular) lobes: ``eval`` is 0 for every given pair, so such lobes are compared on
  sampled pairs: each configuration is sampled with the same ``(wo, uc, u)`` as the reference and
  ``v = f |cos theta_i|`` of the sample is compared (a configuration that picks another lobe or
  direction counts as 0 there, i.e. a full error). Models made only of delta lobes are measured
  this way, and their throughput is that of ``sample``.

Default direction set (:func:`direction_set`): half the pairs stratified (Latin hypercube over
cos theta_o, phi_o, cos theta_i, phi_i; cos from 1e-3 to 1, both hemispheres for transmissive
models), half importance-sampled from the most accurate configuration (its highlights and delta
lobes; stratified uniforms at stratified wo). Deterministic for a seed; another seed gives another
set of the same distribution.

Ranking (why :func:`simplify` is deterministic): "fastest" is decided by a *cost table*, not by a
timing taken during the call (noisy, load dependent). ``bench/tradeoff.py`` measures, on this
machine class, the cost of every configuration of one representative per model family relative to
its most accurate configuration, and ships it as package data (``_knob_costs.json``). Among the
configurations within tolerance, those whose cost is within ``COST_RESOLUTION`` (5 %, the table's
measurement resolution) of the cheapest count as equally fast; of those, the one dropping the most
lobes wins (a lobe within tolerance is removed even where its cost is in the noise: the material
gets simpler), then the most accurate (an approximation that buys no measurable speed is not
taken). A configuration missing from the
table is assumed to cost as much as the most accurate one; a family missing altogether is ranked
by registry order alone (the configuration with the most knobs at their cheapest settings).
:func:`simplify` reports the speedup that table predicts; :func:`tradeoff` shows next to it the
live measurement of its own run (ratios to the most accurate configuration timed back to back,
best of ``repeats``). The table is per-element cost measured single-threaded (bench/TRADEOFF.md):
what the knobs change is arithmetic per direction, which threads do not change.
"""
from .configs import Config, Knob, configurations, family, knobs
from .costs import COST_RESOLUTION, best_time, knob_costs
from .errors import ALBEDO_COS_THETA, FLOOR_FRACTION, DirectionSet, direction_set, relative_error
from .report import METRIC_DESCRIPTIONS, METRICS, SimplifyReport, Table, ToleranceNotMetWarning, simplify, tradeoff

__all__ = ["Knob", "knobs", "Config", "configurations", "DirectionSet", "direction_set", "tradeoff", "simplify",
           "Table", "SimplifyReport", "relative_error", "knob_costs", "family", "best_time", "METRICS",
           "FLOOR_FRACTION", "ALBEDO_COS_THETA", "COST_RESOLUTION", "METRIC_DESCRIPTIONS", "ToleranceNotMetWarning"]
