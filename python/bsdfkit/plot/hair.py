"""Hair views: the longitudinal and azimuthal lobes per path (R, TT, TRT, rest), in the style of
Marschner et al. 2003, d'Eon et al. 2011 and Chiang et al. 2016, and the 3D lobe over the sphere.

The lobe terms Mp, Np and Ap are pbrt-v4's formulas evaluated in float64 by
``bsdfkit.testing.hair_ref`` (the same oracle the tests hold the kernels to); ``hair_lobe3d``
draws the compiled model itself.
"""
from __future__ import annotations

import math

import numpy as np

from ..models.hair import Hair
from ..testing import hair_ref

__all__ = ["hair_lobes", "hair_lobe3d"]

_COLORS = {"R": "C0", "TT": "C3", "TRT": "C2", "rest": "0.45"}
_LUM = np.array([0.212671, 0.715160, 0.072169])


def _check_hair(model):
    if not isinstance(model, Hair):
        raise TypeError(f"model: expected a bsdfkit.Hair, got {type(model).__name__}")
    if not isinstance(model.sigma_a, np.ndarray):   # a sigma_a spectrum: the views draw RGB mode
        from ..models.hair import _sigma_a_rgb
        model = Hair._from_params(dict(model._params, sigma_a=_sigma_a_rgb(model.sigma_a)))
    return model


def _finite(x, name):
    try:
        v = float(x)
    except (TypeError, ValueError):
        raise TypeError(f"{name}: expected a real number, got {type(x).__name__}") from None
    if not math.isfinite(v):
        raise ValueError(f"{name}: must be finite, got {v}")
    return v


def hair_lobes(model, theta_o=30.0, *, fig=None, weighted=True, n=721):
    """Three panels for a ``bsdfkit.Hair`` at longitudinal angle ``theta_o`` (degrees from the
    normal plane, wo's azimuth 0 of pbrt's frame):

    1. longitudinal scattering M_p(theta_i) per lobe (the specular cone theta_i = -theta_o is
       dashed; the cuticle tilt shifts R by -2 alpha, TT by alpha, TRT by 4 alpha);
    2. azimuthal scattering N_p(phi) per lobe at the model's h, phi = phi_i - phi_o in degrees;
    3. the same azimuthal lobes weighted by the attenuation A_p (luminance) on polar axes, the
       cross-section view of Marschner's and d'Eon's figures (phi = 0: back towards wo... read as
       the direction of exit around the fibre).

    Parameters
    ----------
    model : Hair
        A fibre with an offset ``h`` (not the far-field fibre).
    theta_o : float, optional
        wo's longitudinal angle, degrees in [-90, 90].
    fig : matplotlib Figure, optional
        A Figure to draw into (a new pyplot figure otherwise).
    weighted : bool, optional
        Panel 1 shows A_p M_p instead of M_p.
    n : int, optional
        Points per curve.

    Returns
    -------
    matplotlib.figure.Figure
        The figure; ``fig.bsdfkit_data`` holds ``theta_i_deg``, ``phi_deg``, ``Mp`` (4, n),
        ``Np`` (4, n), ``Ap`` (4, 3).

    Raises
    ------
    TypeError
        A model that is not a Hair.
    ValueError
        The far-field fibre (h=None), or theta_o outside [-90, 90].

    Examples
    --------
    >>> import bsdfkit as bk
    >>> from bsdfkit import plot as bkplot
    >>> fig = bkplot.hair_lobes(bk.Hair(h=0.3), n=91)
    >>> fig.bsdfkit_data["Mp"].shape
    (4, 91)
    """
    import matplotlib.pyplot as plt

    m = _check_hair(model)
    if m.h is None:
        raise ValueError("model: hair_lobes needs a fibre offset h (the azimuthal lobes depend on it); "
                         "the far-field fibre (h=None) has no single N_p -- use hair_lobe3d")
    theta_o = _finite(theta_o, "theta_o")
    if not -90.0 <= theta_o <= 90.0:
        raise ValueError(f"theta_o: must be in [-90, 90] degrees, got {theta_o}")
    ti = np.linspace(-90.0, 90.0, n)
    ph = np.linspace(-180.0, 180.0, n)
    t = hair_ref.lobe_terms(m, math.radians(theta_o), np.radians(ti), np.radians(ph))
    lum = t["Ap"] @ _LUM
    if fig is None:
        fig = plt.figure(figsize=(13.5, 4.2), layout="constrained")
    ax1 = fig.add_subplot(1, 3, 1)
    ax2 = fig.add_subplot(1, 3, 2)
    ax3 = fig.add_subplot(1, 3, 3, projection="polar")
    for k, name in enumerate(hair_ref.LOBES):
        c = _COLORS[name]
        mp = t["Mp"][k] * (lum[k] if weighted else 1.0)
        ax1.plot(ti, mp, color=c, lw=1.8, label=f"{name}  (A = {lum[k]:.3g})")
        ax2.plot(ph, t["Np"][k], color=c, lw=1.8, label=name)
        ax3.plot(np.radians(ph), t["Np"][k] * lum[k], color=c, lw=1.8, label=name)
    ax1.axvline(-theta_o, color="k", ls="--", lw=0.8, label="specular cone θi = −θo")
    ax1.set_xlabel("θi (longitudinal, degrees)")
    ax1.set_ylabel("A_p M_p(θi)" if weighted else "M_p(θi)")
    ax1.set_title(f"Longitudinal lobes, θo = {theta_o:g}°", fontsize="medium")
    ax1.set_xlim(-90, 90)
    ax1.set_xticks(np.arange(-90, 91, 30))
    ax1.legend(fontsize="small")
    ax1.grid(alpha=0.3)
    ax2.set_xlabel("φ = φi − φo (degrees)")
    ax2.set_ylabel("N_p(φ)  [1/rad]")
    ax2.set_title(f"Azimuthal lobes, h = {m.h:g}", fontsize="medium")
    ax2.set_xlim(-180, 180)
    ax2.set_xticks(np.arange(-180, 181, 60))
    ax2.grid(alpha=0.3)
    ax2.legend(fontsize="small")
    ax3.set_title("A_p N_p(φ) around the fibre", fontsize="medium")
    ax3.set_theta_zero_location("E")
    ax3.tick_params(labelsize="x-small")
    fig.suptitle(f"Hair  σa = ({', '.join(f'{x:.3g}' for x in m.sigma_a)}), η = {m.eta:g}, "
                 f"βm = {m.beta_m:g}, βn = {m.beta_n:g}, α = {m.alpha:g}°", fontsize="medium")
    fig.bsdfkit_data = dict(theta_i_deg=ti, phi_deg=ph, Mp=t["Mp"], Np=t["Np"], Ap=t["Ap"])
    return fig


def hair_lobe3d(model, theta_o=30.0, phi_o=90.0, *, ax=None, log=False, **kw):
    """3D lobe of ``f |cos wi.z|`` (= sum_p Mp Ap Np, the scattered energy per solid angle) over
    the whole sphere.

    wo is at longitudinal angle ``theta_o`` and azimuth ``phi_o`` (degrees) of the hair frame
    (x = fibre axis; phi from y towards z). Draws with ``bsdfkit.plot.lobe3d``
    (``sphere=True, cosine=True``).

    Parameters
    ----------
    model : Hair
        The fibre.
    theta_o, phi_o : float, optional
        wo's angles in the hair frame, degrees.
    ax : Axes3D, optional
        Where to draw.
    log : bool, optional
        Logarithmic radius.
    **kw
        Passed to :func:`lobe3d`.

    Returns
    -------
    mpl_toolkits.mplot3d.Axes3D
        The 3D Axes of :func:`lobe3d`.

    Raises
    ------
    TypeError
        A model that is not a Hair.
    """
    from ._lobe3d import lobe3d

    m = _check_hair(model)
    th, ph = math.radians(_finite(theta_o, "theta_o")), math.radians(_finite(phi_o, "phi_o"))
    wo = np.array([math.sin(th), math.cos(th) * math.cos(ph), math.cos(th) * math.sin(ph)])
    theta_s = round(math.degrees(math.acos(max(-1.0, min(1.0, wo[2])))), 6)  # lobe3d's spherical angles
    phi_s = round(math.degrees(math.atan2(wo[1], wo[0])), 6) + 0.0
    kw.setdefault("n_theta", 61)
    kw.setdefault("n_phi", 121)
    return lobe3d(m, theta_o=theta_s, phi_o=phi_s, ax=ax, log=log, cosine=True, sphere=True, **kw)
