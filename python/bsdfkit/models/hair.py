"""Hair fibres (Chiang et al. 2016 as in pbrt-v4 ``HairBxDF``)."""
from __future__ import annotations

import math

import numpy as np

from .. import _core
from . import _spectral as _sp
from .base import BxDF, _rgb, _scalar, core_value
from .registry import KnobDecl
from ..spectral.spectrum import Spectrum

__all__ = ["Hair", "EUMELANIN_SIGMA_A", "PHEOMELANIN_SIGMA_A", "sigma_a_from_concentration",
           "sigma_a_from_reflectance", "sigma_a_spectrum_from_reflectance"]

#: Absorption of eumelanin and pheomelanin per unit concentration, per unit fibre radius, RGB
#: (d'Eon et al. 2011 via pbrt-v4 ``SigmaAFromConcentration``; Mitsuba 3 ``hair`` uses the same).
EUMELANIN_SIGMA_A = (0.419, 0.697, 1.37)
PHEOMELANIN_SIGMA_A = (0.187, 0.4, 1.05)
#: Cap on sigma_a from ``from_reflectance`` (a reflectance of 0 maps to +inf); exp(-2e4) is 0.
SIGMA_A_MAX = 1e4


def sigma_a_from_concentration(eumelanin=1.3, pheomelanin=0.0) -> np.ndarray:
    """sigma_a = eumelanin (0.419, 0.697, 1.37) + pheomelanin (0.187, 0.4, 1.05), RGB (pbrt-v4
    ``SigmaAFromConcentration``, which then uplifts this RGB as an ``RGBUnboundedSpectrum``: so
    does bsdfkit's spectral mode, ``wavelengths=``, with any RGB sigma_a). Concentrations >= 0
    (1.3 / 0: pbrt-v4's default brown)."""
    ce = _scalar(eumelanin, "eumelanin", lo=0.0)
    cp = _scalar(pheomelanin, "pheomelanin", lo=0.0)
    return ce * np.asarray(EUMELANIN_SIGMA_A) + cp * np.asarray(PHEOMELANIN_SIGMA_A)


def sigma_a_from_reflectance(color, beta_n=0.3) -> np.ndarray:
    """sigma_a giving roughly the multiply-scattered colour ``color`` (Chiang 2016 eq. 9; pbrt-v4
    ``SigmaAFromReflectance``): sigma_a = (ln c / (5.969 - 0.215 bn + 2.532 bn^2 - 10.73 bn^3
    + 5.574 bn^4 + 0.245 bn^5))^2 per channel. ``color`` in [0, 1] (scalar or RGB); a channel of
    0 (sigma_a = inf) is capped at ``SIGMA_A_MAX``."""
    c = _rgb(color, "color", lo=0.0, hi=1.0)
    bn = _scalar(beta_n, "beta_n", lo=0.0, hi=1.0)
    with np.errstate(divide="ignore"):
        s = (np.log(c) / _reflectance_denominator(bn)) ** 2
    return np.minimum(s, SIGMA_A_MAX)


def _reflectance_denominator(bn: float) -> float:
    # Chiang 2016 eq. 9's polynomial in beta_n (pbrt-v4 SigmaAFromReflectance)
    return 5.969 - 0.215 * bn + 2.532 * bn**2 - 10.73 * bn**3 + 5.574 * bn**4 + 0.245 * bn**5


def sigma_a_spectrum_from_reflectance(color, beta_n=0.3) -> Spectrum:
    """sigma_a(lambda) of a colour as pbrt-v4's ``HairMaterial`` computes it in its spectral
    renders: the colour as a reflectance spectrum (an RGB uplifted as ``RGBAlbedoSpectrum``, Jakob
    & Hanika 2019; or a ``bsdfkit.Spectrum``), clamped to [0, 1], then ``SigmaAFromReflectance``
    per wavelength (pbrt-v4 materials.h ``HairMaterial::GetBxDF``). Tabulated every nm over
    [360, 830] (linear between, as the kernels read spectra); a value 0 is capped at
    ``SIGMA_A_MAX``. Its RGB mode (projection, no illuminant) differs from
    ``sigma_a_from_reflectance`` of the RGB colour: the formula is not linear."""
    c = _sp.spectrum_or_rgb(color, "color", lo=0.0, hi=1.0)
    bn = _scalar(beta_n, "beta_n", lo=0.0, hi=1.0)
    rs = c if isinstance(c, Spectrum) else Spectrum.from_rgb(c, "reflectance")
    v = np.clip(rs(_sp.DENSE_WAVELENGTHS), 0.0, 1.0)
    with np.errstate(divide="ignore"):
        s = (np.log(v) / _reflectance_denominator(bn)) ** 2
    return Spectrum(_sp.DENSE_WAVELENGTHS, np.minimum(s, SIGMA_A_MAX))


def _sigma_a_rgb(v) -> np.ndarray:
    """RGB-mode sigma_a: as given, or a spectrum projected to linear sRGB without an illuminant
    (Mitsuba 3's rule for unbounded spectra such as IOR data), clamped at 0; a constant is itself."""
    if not isinstance(v, Spectrum):
        return v
    if v.is_constant:
        return np.full(3, float(v(np.float64(550.0))))
    return np.maximum(v.to_rgb("unbounded", None), 0.0)


def _h(h):
    if h is None:
        return None
    return _scalar(h, "h", lo=-1.0, hi=1.0, varying=True)


def _nodes(n):
    if isinstance(n, (bool, np.bool_)) or not isinstance(n, (int, np.integer)):
        raise ValueError(f"nodes: expected an integer in [1, 64], got {n!r}")
    if not 1 <= n <= 64:
        raise ValueError(f"nodes: must be in [1, 64], got {n}")
    return int(n)


class Hair(BxDF):
    """A hair fibre: Chiang, Bitterli, Tappan & Burley 2016, "A Practical and Controllable Hair and
    Fur Model for Production Path Tracing", exactly as pbrt-v4's ``HairBxDF`` (lobes R, TT, TRT of
    Marschner et al. 2003 plus one lobe for all longer paths; d'Eon et al. 2011's longitudinal
    Mp in log space for small variance; logistic azimuthal lobes).

    sigma_a: absorption coefficient inside the fibre per unit fibre *radius*, scalar or RGB >= 0
    (see ``from_concentration`` and ``from_reflectance``; None: pbrt-v4's default, eumelanin 1.3,
    a brown). eta: IOR of the fibre (>= 1; 1.55).
    beta_m, beta_n: longitudinal and azimuthal roughness in [0.01, 1] (pbrt-v4's material clamps
    to the same range; v_p and s follow Chiang 2016 eqs. 7-8). alpha: cuticle scale tilt in
    **degrees** in [-90, 90] (R shifts by -2 alpha, TT by alpha, TRT by 4 alpha). h: offset across
    the fibre in [-1, 1] at which the ray from wo hits it (pbrt-v4 takes h = -1 + 2 v of the curve
    uv), or **None: the far-field fibre**, f averaged over h in [-1, 1], (1/2) int f(h) dh,
    integrated in gamma = asin h (smooth there; dh = cos gamma dgamma) by ``nodes``-point
    Gauss-Legendre (default 64, the most accurate; at most 64) with the weights normalised to 1; sampled as the same
    mixture (exact pdf). ``nodes`` times the cost of one h. For fibres thinner than a pixel.
    ``nodes`` is an accuracy knob (``bk.tradeoff``): sharp azimuthal lobes (small beta_n) need
    more nodes (error of f |cos| as a fraction of its peak against a converged rule, bench/HAIR.md:
    16 nodes 0.17 at beta_n = 0.3, 5e-3 at 0.5; 64 nodes 1e-6 at 0.3, 5e-2 at 0.1);
    ``bk.simplify`` picks the fewest nodes that meet a tolerance. It does nothing for a single h.

    **Frame** (pbrt-v4): local **x is the fibre axis** (tangent; sin theta = w.x, theta the
    longitudinal angle), **y and z span the normal plane** with azimuth phi = atan2(w.z, w.y);
    **z is the normal of the ribbon** the fibre is rendered as (pbrt-v4 curves face the ray), so
    a renderer's shading normal is +z. ``f`` is defined over the **whole sphere** (there is no
    "below the surface") and, as in pbrt-v4, divided by |wi.z| so that the |cos| a renderer
    multiplies by cancels: f |wi.z| = sum_p Mp Ap Np. The transport mode is ignored (as pbrt-v4).
    Not reciprocal. Sampling is exact for sigma_a = 0 (weights 1).

    **Spectral mode** (``wavelengths=``, pbrt-v4's HairBxDF is spectral): sigma_a per wavelength,
    eta, beta_m, beta_n, alpha and h wavelength-independent. ``sigma_a`` may be a
    ``bsdfkit.Spectrum`` (>= 0 over [360, 830] nm); an RGB sigma_a (also from
    ``from_concentration``: pbrt-v4's ``SigmaAFromConcentration`` computes RGB, then uplifts) is
    uplifted as pbrt-v4's ``RGBUnboundedSpectrum`` (Jakob & Hanika 2019);
    ``from_reflectance(color, spectral=True)`` is pbrt-v4's spectral route for a colour
    (``sigma_a_spectrum_from_reflectance``). f is the RGB model's per wavelength. The lobe choice
    of ``sample`` and ``pdf`` weights the lobes by A_p **averaged over the 4 wavelengths** (pbrt-v4
    ``ApPDF``), so the spectral pdf differs from the RGB pdf (averaged over the 3 RGB channels) by
    that average and depends on the wavelengths; ``sample`` and ``pdf`` agree with each other.
    RGB mode projects a sigma_a spectrum to linear sRGB without an illuminant (clamped at 0).

    Parameters
    ----------
    sigma_a : float or RGB or Spectrum, optional
        Absorption coefficient inside the fibre per unit fibre radius, >= 0; None: pbrt-v4's
        default (eumelanin 1.3).
    eta : float, optional
        IOR of the fibre (>= 1; default 1.55).
    beta_m, beta_n : float, optional
        Longitudinal and azimuthal roughness in [0.01, 1] (default 0.3 each).
    alpha : float, optional
        Cuticle scale tilt in degrees in [-90, 90] (default 2).
    h : float or None, optional
        Offset across the fibre in [-1, 1] (default 0), or None: the far-field fibre.
    nodes : int, optional
        Gauss-Legendre nodes of the far-field average (at most 64, the default).

    Raises
    ------
    ValueError
        A value out of its range, naming the parameter (TypeError for a wrong type).

    Examples
    --------
    >>> import numpy as np, bsdfkit as bk
    >>> m = bk.Hair.from_concentration(1.3, beta_m=0.3, beta_n=0.3)
    >>> m.eval(bk.direction(1.2, 0.3), bk.direction(2.0, 2.5)).shape
    (3,)
    """

    __slots__ = ()
    aliases = ("fiber", "fibre")
    # (the far-field fibre, h=None, costs 16 single-h kernels: its chi2 / oracle tests live in
    # tests/models/test_hair.py rather than in every generic contract)
    examples = {"brown": "hair", "blonde, off-centre": "hair concentration=0.3 h=0.5",
                "dark rough": "hair concentration=8 beta_m=0.5 beta_n=0.5", "teal": "hair reflectance=0.1,0.5,0.5"}
    description = "Hair fibre of Chiang et al. 2016 (pbrt-v4 HairBxDF): R, TT, TRT lobes + rest"
    # f lives on the whole sphere (no "below the surface"; f is divided by |wi.z|): both sides of
    # z are valid (two_sided), the lobes through the fibre are still "reflection" by pbrt-v4's flags
    full_sphere = True
    energy_conserving = True
    exact_eval = True
    reciprocal = False   # pbrt-v4's hair is not (the theta_o tilt and Ap depend on wo)
    two_sided = True
    transmission = False
    delta_only = False
    mitsuba = "hair"
    varying_params = {"sigma_a": 3, "eta": 1, "beta_m": 1, "beta_n": 1, "alpha": 1, "h": 1}
    # pbrt-v4's HairBxDF has no accuracy setting (p_max = 3 is fixed); the far-field fibre's
    # quadrature order is one (bench/HAIR.md: its error against 64 nodes)
    knobs = (KnobDecl("nodes", (64, 32, 16, 8, 4), "approximation",
                      "Gauss-Legendre nodes of the far-field fibre's integral over h",
                      moot=lambda p: None if p["h"] is None else "a single h (h is not None)"),)

    def cost_family(self) -> str:
        return "Hair/far-field" if self._params["h"] is None else "Hair"   # far field: 16 single-h kernels

    def to_mitsuba(self, approximate: bool = False) -> dict:
        """Mitsuba 3 ``hair`` (sigma_a form, ext_ior 1). Mitsuba has no ``h``: it derives it from
        wo (``bsdfkit.testing.hair_ref.wo_for_h``), and its fibre axis is local y where bsdfkit's
        (pbrt-v4's) is x (``hair_ref.to_mitsuba_frame``); so only h = 0 converts, other h and the
        far-field fibre (h=None) raise ValueError, also with ``approximate=True``."""
        self._refuse_varying("to_mitsuba")
        from ._mitsuba_export import check_approximate
        check_approximate(approximate)
        if self._params["h"] != 0.0:
            raise ValueError(f"Hair(h={self._params['h']!r}): Mitsuba 3's hair has no h parameter (it derives h "
                             "from the direction); only h=0 converts")
        from ..testing.hair_ref import mitsuba_dict
        return mitsuba_dict(dict(self._params, sigma_a=_sigma_a_rgb(self._params["sigma_a"])))

    def __init__(self, sigma_a=None, eta=1.55, beta_m=0.3, beta_n=0.3, alpha=2.0, h=0.0, nodes=64):
        """A Hair: the parameters are described in the class docstring (``help(bsdfkit.Hair)``);
        a bad value raises ValueError (TypeError for a wrong type) naming the parameter."""
        if sigma_a is None:  # pbrt-v4's default: eumelanin 1.3
            sigma_a = sigma_a_from_concentration(1.3, 0.0)
        super().__init__(sigma_a=_sp.spectrum_or_rgb(sigma_a, "sigma_a", lo=0.0, varying=True),
                         eta=_scalar(eta, "eta", lo=1.0, varying=True),
                         beta_m=_scalar(beta_m, "beta_m", lo=0.01, hi=1.0, varying=True),
                         beta_n=_scalar(beta_n, "beta_n", lo=0.01, hi=1.0, varying=True),
                         alpha=_scalar(alpha, "alpha", lo=-90.0, hi=90.0, varying=True),
                         h=_h(h), nodes=_nodes(nodes))

    @classmethod
    def from_concentration(cls, eumelanin=1.3, pheomelanin=0.0, **kw) -> "Hair":
        """Hair whose sigma_a comes from melanin concentrations (see
        ``sigma_a_from_concentration``); other keywords as ``Hair``."""
        return cls(sigma_a_from_concentration(eumelanin, pheomelanin), **kw)

    @classmethod
    def from_reflectance(cls, color, *, spectral: bool = False, **kw) -> "Hair":
        """Hair of roughly the given multiply-scattered colour (see ``sigma_a_from_reflectance``,
        which uses this model's ``beta_n``); other keywords as ``Hair``. ``spectral=True`` (or
        ``color`` a ``bsdfkit.Spectrum``): sigma_a is the spectrum pbrt-v4 computes per wavelength
        (``sigma_a_spectrum_from_reflectance``); otherwise an RGB sigma_a (uplifted as unbounded in
        spectral mode)."""
        if not isinstance(spectral, (bool, np.bool_)):
            raise TypeError(f"spectral: expected True or False, got {spectral!r}")
        if spectral or isinstance(color, Spectrum):
            return cls(sigma_a_spectrum_from_reflectance(color, kw.get("beta_n", 0.3)), **kw)
        return cls(sigma_a_from_reflectance(color, kw.get("beta_n", 0.3)), **kw)

    @classmethod
    def _from_params(cls, p):
        return cls(**p)

    def __repr__(self):
        if self.varying:
            return BxDF.__repr__(self)
        p = self._params
        nodes = "" if p["nodes"] == 64 else f", nodes={p['nodes']!r}"
        sa = p["sigma_a"]
        sa = repr(sa) if isinstance(sa, Spectrum) else f"[{', '.join(repr(float(x)) for x in sa)}]"
        return (f"Hair(sigma_a={sa}, eta={p['eta']!r}, "
                f"beta_m={p['beta_m']!r}, beta_n={p['beta_n']!r}, alpha={p['alpha']!r}, h={p['h']!r}{nodes})")

    def describe(self) -> str:
        p = self._params
        if self.varying or not isinstance(p["sigma_a"], Spectrum):
            return super().describe()
        q = dict(p, sigma_a=_sigma_a_rgb(p["sigma_a"]))   # the spec text of the RGB projection
        return type(self)._from_params(q).describe() + " (sigma_a spectral)"

    def _core_kwargs(self) -> dict:
        p = self._params
        kw = dict(sigma_a=core_value(_sigma_a_rgb(p["sigma_a"])), eta=p["eta"], beta_m=p["beta_m"], beta_n=p["beta_n"],
                  alpha=p["alpha"])
        if p["h"] is None:
            kw["nodes"] = p["nodes"]
        else:
            kw["h"] = p["h"]
        return kw

    def _make_core(self):
        return (_core.HairFarField if self._params["h"] is None else _core.Hair)(**self._core_kwargs())

