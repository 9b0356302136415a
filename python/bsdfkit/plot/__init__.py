"""Matplotlib views of bsdfkit models, one module per view.

pyplot is imported only when a function has to create its own figure (``ax=None``), so the
package is safe under any backend, including Agg on headless machines. Every function accepts
one model or a list of models (overlaid, with a legend) and returns the Axes it drew on, with
the plotted numbers attached as ``ax.bsdfkit_data`` (a dict of per-model lists) for tests and
further processing.

Views: :func:`polar` (in-plane lobe slices), :func:`lobe3d`, :func:`hemisphere`, :func:`halfdiff`
(Rusinkiewicz angles), :func:`albedo`, :func:`samples` / :func:`sample_stats` (sampling against
the pdf), :func:`overview` (several views side by side), :func:`gallery` (one row per registered
model), :func:`explore` (widgets), :func:`pareto` (a trade-off table), :func:`hair_lobes` /
:func:`hair_lobe3d` (a hair fibre's lobes per path, module ``hair``). Shared helpers live in
``_common``.

Angle conventions of :func:`polar`: the slice lies in the plane of azimuth ``phi_plane``
(degrees). A direction in it is given by a signed angle ``t`` (degrees, from the normal,
positive towards azimuth ``phi_plane``) and is ``wi = (sin t cos phi, sin t sin phi, cos t)``.
``wo`` sits at ``t = -theta_o``, i.e. ``wo = bk.direction(radians(theta_o), radians(phi_plane) + pi)``,
so the mirror direction is at ``t = +theta_o``, reflection is drawn above the horizon and
transmission below it. 0 deg (the normal) is at the top of the plot.
"""
from ..models.describe import describe
from ._albedo import albedo
from ._common import LUMINANCE_WEIGHTS, luminance
from ._difference import difference, difference_model
from ._explore import Explorer, explore
from ._gallery import gallery
from ._halfdiff import halfdiff
from .hair import hair_lobe3d, hair_lobes
from ._hemisphere import hemisphere
from ._lobe3d import lobe3d
from ._overview import VIEWS, overview
from ._pareto import pareto
from ._polar import polar
from ._samples import sample_stats, samples

__all__ = ["pareto", "difference", "difference_model", "polar", "lobe3d", "hemisphere", "halfdiff", "albedo", "samples", "sample_stats", "overview",
           "gallery", "explore", "Explorer", "hair_lobes", "hair_lobe3d", "describe", "luminance", "LUMINANCE_WEIGHTS", "VIEWS"]
