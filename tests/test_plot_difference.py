"""The difference view says what it plots, and the polar scale ignores a horizon singularity
(issue 50, item 10). The difference view labelled a relative difference "f [1/sr]"; in the polar
view one sample at θi = 90° could set the radial scale (or the log floor) and flatten the plot.
"""
import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit import plot as bkplot

pytest.importorskip("matplotlib")


def _hemi_label(ax):
    return ax.bsdfkit_data["colorbar"].ax.get_ylabel() + ax.bsdfkit_data["colorbar"].ax.get_xlabel()


def test_difference_views_are_labelled_as_a_relative_difference():
    a = bk.Conductor.from_metal("Au", alpha=0.3)
    b = bk.Conductor.from_metal("Au", alpha=0.3, masking="separable")
    ax = bkplot.difference(a, b, "hemisphere")
    lab = _hemi_label(ax)
    assert "relative" in lab and "1/sr" not in lab
    ax = bkplot.difference(a, b, "halfdiff")
    assert "relative" in ax.bsdfkit_data["colorbar"].ax.get_ylabel()
    ax = bkplot.difference(a, b, "polar")
    assert "1/sr" not in ax.get_title() and "relative difference" in ax.get_title()
    with pytest.raises(ValueError, match="cosine"):
        bkplot.difference(a, b, "polar", cosine=True)
    # the plain views keep the unit of f
    assert "f [1/sr]" in _hemi_label(bkplot.hemisphere(a))


def _spike():
    """f = 1/pi everywhere, 1e6 exactly on the horizon."""
    def f(wo, wi):
        v = np.where(np.abs(wi[..., 2]) < 1e-12, 1e6, 1 / np.pi)
        return np.repeat(v[..., None], 3, axis=-1)
    return bk.Custom(f=f, name="spike at the horizon")


@pytest.mark.parametrize("log", [False, True])
def test_polar_scale_ignores_the_horizon_sample(log):
    ax = bkplot.polar(_spike(), theta_o=30.0, log=log, legend=False)
    lo, hi = ax.get_ylim()
    if log:   # 4 decades below the largest value off the horizon (1/pi): floor 1e-4, not 1e2
        assert ax.bsdfkit_data["log_floor"] == pytest.approx(1e-4)
    else:     # the radius ends just above 1/pi, not at 1e6
        assert 1 / np.pi <= hi < 0.5
    d = ax.bsdfkit_data
    assert np.max(d["value"][0]) == pytest.approx(1e6)    # the sample is still there, clipped at the rim
