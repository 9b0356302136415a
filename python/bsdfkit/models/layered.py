"""Layered models: pbrt-v4's stochastic ``CoatedDiffuse`` and ``CoatedConductor``."""
from __future__ import annotations

import numpy as np

from .. import _core
from .._arrays import check_int
from ..spectral.spectrum import Spectrum
from . import _spectral as _sp
from .base import (_MASKING, BxDF, _alphas, _masking, _pick_alpha, _rgb, _scalar, core_value, fmt_value,
                   masking_knob)
from .conductor import METALS
from .registry import KnobDecl

__all__ = ["CoatedDiffuse", "CoatedConductor"]

_LAYER_PARAMS = """
    thickness : float, optional
        Slab thickness in mean free paths of the medium (sigma_t = 1), >= 0; pbrt-v4 floors it
        at FLT_MIN. With albedo 0 it still attenuates: exp(-thickness / |cos|) per pass.
    albedo : float or RGB or Spectrum, optional
        Single-scattering albedo of the medium, scalar or RGB in [0, 1] (0: no medium, only
        absorption by the thickness).
    g : float, optional
        Henyey-Greenstein asymmetry in [-1, 1] (clamped to +-0.99 as pbrt-v4's sampler does).
    max_depth : int, optional
        Longest random walk (>= 1); deeper paths are truncated (a bias), pbrt default 10.
    n_samples : int, optional
        Random walks averaged per evaluation (>= 1): noise falls as 1/sqrt(n_samples), cost
        grows linearly.
    seed : int, optional
        Picks the realization (integer >= 0). ``eval``/``pdf``/``sample`` are deterministic
        functions of (seed, wo, wi) / (seed, wo, uc, u): bit-identical for any thread count,
        chunking or array position; average over seeds for the expectation.
    mis : {"pbrt", "consistent"}, optional
        "pbrt" (default) is pbrt-v4's f() estimator as the book defines it. Its MIS weight for
        leaving through a rough coating after a base or medium sample compares the sample's
        density of the inner direction with top.PDF(-w, wi), a density of wi: the two strategies'
        weights do not sum to one and f() is biased high with a rough coat (measured +5 to +8 %
        of the albedo for alpha 0.1-0.3; sample() is not affected). "consistent" uses the
        density of the same inner direction under the other strategy (top.PDF(wi, -w) in the
        adjoint mode), so the weights sum to one.
    method : {"stochastic", "analytic"}, optional
        "stochastic" (default, the model: pbrt-v4's random walk) or "analytic", a deterministic
        closed-form approximation of the same layered material (see Notes).

    Raises
    ------
    ValueError
        A value out of its range, naming the parameter (TypeError for a wrong type).
"""

_LAYER_DOC = """
    Notes
    -----
    Energy under a rough coat: the coat is pbrt-v4's rough dielectric interface, whose
    single-scattering microfacet model loses energy, most of it from inside beyond the critical
    angle. A white, lossless CoatedDiffuse (reflectance 1, medium albedo 1, eta 1.5) reflects
    1.000 with a smooth coat, 0.975 at alpha 0.05 and 0.694 at alpha 0.3 (theta_o = 46 deg); the
    interface's own loss, measured from both sides, predicts these to 1e-4 (the walk loses
    nothing else; ``tests/models/test_layered_energy.py``). No energy compensation covers the
    dielectric interface yet.

    ``method="analytic"`` is a deterministic closed-form approximation (Weidlich & Wilkie
        2007: the coating's reflection lobe, the base evaluated at the refracted directions and
        attenuated by (1 - F(wo)) (1 - F(wi)) / eta^2 and by the absorption exp(-thickness
        (1/cos_o' + 1/cos_i')) along the refracted paths, the internal reflections summed as
        1 / (1 - rho_base Fdr_int t_d^2); plus the medium's single scattering, Hanrahan &
        Krueger 1993). It is cheap and noise-free but biased (no multiple scattering in the
        medium, no blurring of the base by a rough coat, Fresnel at the macro normal). Its
        error against the converged walk (relative RMS of f |cos| over uniform pairs,
        bench/LAYERED.md): varnished wood 0.02, car paint 0.06 (+10 % in total), lacquer with a
        scattering medium (albedo 0.8, thickness 0.2) 0.31 (-32 %: no multiple scattering),
        smooth coat over a smooth metal 0.001 (exact series); 8-13x faster than one walk
        (n_samples=1). Its eval / pdf / sample are exact and consistent (sample()
        equals eval() / pdf()), reciprocal, and ignore max_depth, n_samples, seed and mis.
        A knob of the trade-off registry (an approximation: ``bk.simplify`` may choose it).

    Spectral mode (``wavelengths=``, both methods): ``reflectance`` / ``conductor_eta`` /
    ``conductor_k`` / ``albedo`` may be ``bsdfkit.Spectrum`` values (RGB ones are uplifted, Jakob &
    Hanika 2019: bounded for reflectance and albedo, unbounded for eta and k) and are evaluated per
    wavelength. The coating's IOR and roughness and the thickness are wavelength-independent.
    method="analytic": the internal-reflection sum M and the metal's hemispherical albedo per
    wavelength; the lobe choice (its weights from the RGB projection) is wavelength-independent,
    hence pdf has one value per element. method="stochastic": the walk carries 4 channels (pbrt-v4's
    SampledSpectrum): the 4 wavelengths share one path (the same hashed generator as in RGB mode),
    the base and the medium act per wavelength and Russian roulette reads the largest of the 4
    throughputs, so each wavelength is an unbiased estimate of its own f, and a grey spectrum gives
    exactly the RGB model's values (same seed, same path, bit for bit); pdf is the walk's (one
    value). RGB mode projects spectra to linear sRGB (D65 for reflectance / albedo, no illuminant
    for eta and k) and runs the walk on the 3 channels.

    The estimators are pbrt-v4's (book section 14.3; Guo et al. 2018): ``eval`` is a stochastic
    estimate of f (unbiased up to max_depth), ``sample`` returns a path sample whose ``pdf`` is
    only proportional to the true density (``pdf_is_proportional`` is True: use
    ``s.weight`` = f |cos| / pdf, which is exact in expectation), and ``pdf`` is pbrt's
    approximate, stochastic density mixed with 10 % of the uniform sphere density 1 / (4 pi), so
    it is > 0 everywhere (also across the surface, where f = 0). Two-sided; reflection only.
    Neither eval nor pdf vectorizes (a data-dependent random walk per element).
"""


_MIS = ("pbrt", "consistent")
_METHODS = ("stochastic", "analytic")


def _layer(thickness, albedo, g, max_depth, n_samples, seed, mis, method="stochastic"):
    t = _scalar(thickness, "thickness", lo=0.0, varying=True)
    a = _sp.spectrum_or_rgb(albedo, "albedo", lo=0.0, hi=1.0, varying=True)
    gg = _scalar(g, "g", lo=-1.0, hi=1.0, varying=True)
    md = check_int(max_depth, "max_depth", 1)
    ns = check_int(n_samples, "n_samples", 1)
    sd = check_int(seed, "seed", 0)
    if sd >= 2 ** 31:
        raise ValueError(f"seed: must be < 2**31, got {sd}")
    if md > 1_000_000 or ns > 1_000_000:
        raise ValueError("max_depth, n_samples: must be <= 1e6")
    # one direction pair runs up to n_samples walks of max_depth steps on one thread, between two
    # of the pool's interrupt checks: 1e4 x 1e4 takes ~1 s there, 1e6 x 1e6 would take days
    if md * ns > 100_000_000:
        raise ValueError(f"max_depth * n_samples: must be <= 1e8 (random-walk steps per direction pair), "
                         f"got {md} * {ns} = {md * ns:.3g}")
    if mis not in _MIS:
        raise ValueError(f"mis: must be one of {list(_MIS)}, got {mis!r}")
    if method not in _METHODS:
        raise ValueError(f"method: must be one of {list(_METHODS)}, got {method!r}")
    return dict(thickness=t, albedo=a, g=gg, max_depth=md, n_samples=ns, seed=sd, mis=mis, method=method)


def _layer_kw(p):
    return dict(thickness=p["thickness"], albedo=core_value(_sp.rgb_of(p["albedo"], "reflectance")), g=p["g"],
                max_depth=p["max_depth"],
                n_samples=p["n_samples"], seed=p["seed"], consistent_mis=p["mis"] == "consistent")


def _with_own(name, settings):
    """Knob settings, most accurate (largest) first, including the instance's own value."""
    return lambda p: tuple(sorted(set(settings) | {p[name]}, reverse=True))


def _analytic(p):
    return "analytic method: no random walk" if p["method"] == "analytic" else None


#: The layered models' knobs: the method, the estimator's sample count and walk depth are
#: approximations (the same material, computed by a biased closed form, noisier or truncated);
#: the MIS rule and the masking are modelling choices ("pbrt" is biased high with a rough coat,
#: so it is a different f()).
_KNOBS = (KnobDecl("method", _METHODS, "approximation",
                   "stochastic random walk (the model) or the analytic closed-form approximation (biased)"),
          KnobDecl("n_samples", _with_own("n_samples", (64, 32, 16, 8, 4, 2, 1)), "approximation",
                   "random walks averaged per evaluation", moot=_analytic),
          KnobDecl("max_depth", _with_own("max_depth", (100, 20, 10, 5, 2, 1)), "approximation",
                   "longest random walk (deeper ones are cut)", moot=_analytic),
          KnobDecl("mis", ("consistent", "pbrt"), "modelling",
                   "exit MIS weight: consistent (unbiased) or pbrt-v4's (biased high with a rough coat)",
                   moot=_analytic),
          masking_knob(None))


class _ByMethod:
    """A capability flag that depends on ``method``: the class value (read by the registry and
    by code holding only the class) is the stochastic model's; an instance answers for itself
    (the analytic method is an exact, reciprocal closed form)."""

    def __init__(self, stochastic: bool, analytic: bool):
        """A None: the parameters are described in the class docstring (``help(bsdfkit.None)``);
        a bad value raises ValueError (TypeError for a wrong type) naming the parameter."""
        self.stochastic, self.analytic = stochastic, analytic

    def __get__(self, obj, cls=None):
        if obj is None:
            return self.stochastic
        return self.analytic if obj._params["method"] == "analytic" else self.stochastic


#: Cost of a random walk per evaluation against max_depth, relative to max_depth = 10 (Russian
#: roulette ends most walks early; bench/LAYERED.md, CoatedDiffuse and CoatedConductor rows).
_DEPTH_COST = ((1, 0.5), (2, 0.68), (5, 1.0), (10, 1.0), (20, 1.05), (50, 1.1), (100, 1.1))
#: Cost of the analytic method relative to one random walk (bench/LAYERED.md).
ANALYTIC_COST = 0.1   # measured 8-13x faster than n_samples=1 (bench/LAYERED.md)


def _relative_cost(params, dtype=None) -> float:
    """The cost model the trade-off registry ranks these models by (no measured cost table for
    stochastic families): linear in n_samples, a step function of max_depth, the analytic method
    a fraction of one walk; precision is taken as free."""
    if params["method"] == "analytic":
        return ANALYTIC_COST
    d = params["max_depth"]
    depth = next((c for m, c in _DEPTH_COST if d <= m), _DEPTH_COST[-1][1])
    return params["n_samples"] * depth


def _medium(p) -> str:
    return ", medium" if np.any(np.asarray(_sp.rgb_of(p["albedo"], "reflectance")) > 0) else ""


def _method_text(p) -> str:
    return ", analytic" if p["method"] == "analytic" else ""


class _AnalyticSpectral:
    """Spectral forms exist for both methods (the analytic closed form: batch_spectral.h; the
    random walk with 4 channels: spectral/layered_spectral.h; BxDF._has_spectral_kernel reads them
    from _core). The ``color`` knob of the trade-off
    registry (tuning/configs.py reads ``_spectral_ok``) applies to the analytic method only: the
    walk's RGB-versus-spectral error would be measured through its own noise."""

    @staticmethod
    def _spectral_ok(p) -> bool:
        return p["method"] == "analytic"

    def _has_medium(self) -> bool:
        """The walk samples the medium: the albedo is not 0 (over [360, 830] nm for a spectrum)."""
        a = self._params["albedo"]
        if isinstance(a, Spectrum):
            return _sp.spectral_max(a, "reflectance") > 0
        return bool(np.any(np.asarray(a) > 0))


class CoatedDiffuse(_AnalyticSpectral, BxDF):
    __doc__ = """Diffuse base under a dielectric coating with an optional scattering medium between them:
    pbrt-v4's ``CoatedDiffuseBxDF`` (``LayeredBxDF<DielectricBxDF, DiffuseBxDF, true>``).

    Parameters
    ----------
    reflectance : float or RGB or Spectrum, optional
        Albedo of the Lambertian base, scalar or RGB in [0, 1].
    eta : float, optional
        Relative IOR of the coating (> 0; 1 = index matched, the coating disappears).
    alpha, alpha_x, alpha_y : float, optional
        GGX alpha of the coating (< 1e-3: smooth), as in ``Dielectric``.
    masking : {"correlated", "separable"}, optional
        The coating's masking-shadowing: pbrt-v4's height-correlated Smith (default) or G1 G1.""" \
        + _LAYER_PARAMS + """
    Examples
    --------
    >>> import numpy as np, bsdfkit as bk
    >>> m = bk.CoatedDiffuse([0.6, 0.35, 0.15], alpha=0.05, method="analytic")
    >>> m.eval(bk.direction(0.5, 0.0), bk.direction(0.7, 2.0)).shape
    (3,)
    """ + _LAYER_DOC

    __slots__ = ()

    aliases = ()
    examples = {"varnished wood": "coated_diffuse reflectance=0.6,0.35,0.15 alpha=0.05",
                "lacquer with a scattering medium": "coated_diffuse reflectance=0.2 albedo=0.8 thickness=0.2 g=0.3",
                "varnished wood, analytic": "coated_diffuse reflectance=0.6,0.35,0.15 alpha=0.05 method=analytic",
                "lacquer with a medium, analytic":
                    "coated_diffuse reflectance=0.2 albedo=0.8 thickness=0.2 g=0.3 method=analytic"}
    description = "diffuse base under a dielectric coat with an optional HG medium (pbrt-v4, stochastic)"
    # bk.fit bounds (gradients: method="analytic" only)
    param_ranges = {"reflectance": (0.0, 1.0), "eta": (1.001, 4.0), "alpha_x": (1e-3, 2.0), "alpha_y": (1e-3, 2.0),
                    "thickness": (0.0, 10.0), "albedo": (0.0, 1.0), "g": (-0.99, 0.99)}
    varying_params = {"reflectance": 3, "eta": 1, "alpha_x": 1, "alpha_y": 1, "thickness": 1, "albedo": 3, "g": 1}
    # reciprocal = False: each eval is one random-walk realization seeded by (wo, wi), so
    # f(wo, wi) != f(wi, wo) call by call (and pbrt's MIS rule is not reciprocal in expectation)
    energy_conserving, two_sided, transmission, delta_only = True, True, False, False
    exact_eval, reciprocal = _ByMethod(False, True), _ByMethod(False, True)   # per instance: see _ByMethod
    mitsuba = None
    knobs = _KNOBS

    def to_mitsuba(self, approximate: bool = False) -> dict:
        """Raises NotImplementedError: Mitsuba 3 has no plugin for pbrt-v4's stochastic layered
        BSDFs (its ``plastic`` is a different, closed-form coating model: ``bsdfkit.Plastic``)."""
        from ._mitsuba_export import no_plugin
        no_plugin(self, approximate, "Mitsuba 3 has no plugin for pbrt-v4's layered (coated) BSDFs; "
                  "bsdfkit.Plastic is the coating model Mitsuba has (plastic / roughplastic)")

    def __init__(self, reflectance=0.5, eta=1.5, alpha=None, alpha_x=None, alpha_y=None, thickness=0.01,
                 albedo=0.0, g=0.0, max_depth=10, n_samples=1, seed=0, masking="correlated", mis="pbrt",
                 method="stochastic"):
        """A CoatedDiffuse: the parameters are described in the class docstring (``help(bsdfkit.CoatedDiffuse)``);
        a bad value raises ValueError (TypeError for a wrong type) naming the parameter."""
        ax, ay = _alphas(alpha, alpha_x, alpha_y, varying=True)
        super().__init__(reflectance=_sp.spectrum_or_rgb(reflectance, "reflectance", lo=0.0, hi=1.0, varying=True),
                         eta=_scalar(eta, "eta", lo=0.0, lo_open=True, varying=True), alpha_x=ax, alpha_y=ay,
                         **_layer(thickness, albedo, g, max_depth, n_samples, seed, mis, method),
                         masking=_masking(masking))

    @classmethod
    def _from_params(cls, p):
        return cls(**p)

    def _make_core(self):
        p = self._params
        core = _core.CoatedDiffuseAnalytic if p["method"] == "analytic" else _core.CoatedDiffuse
        return core(**self._core_kwargs())

    def _core_kwargs(self) -> dict:
        p = self._params
        return dict(reflectance=core_value(_sp.rgb_of(p["reflectance"], "reflectance")), eta=p["eta"],
                    alpha_x=p["alpha_x"], alpha_y=p["alpha_y"], masking=_MASKING[p["masking"]], **_layer_kw(p))

    def _spectral_inputs(self) -> dict:
        # the walk (spectral/layered_spectral.h) samples the medium only where the whole albedo
        # spectrum is not 0; the analytic form (batch_spectral.h) has no such input
        return {} if self._params["method"] == "analytic" else {"has_albedo": self._has_medium()}

    @staticmethod
    def relative_cost(params, dtype=None) -> float:
        """Relative cost of a configuration (the tuning registry's cost model; see _relative_cost)."""
        return _relative_cost(params, dtype)

    def cost_family(self) -> str:
        return "CoatedDiffuse" + (_medium(self._params) + _method_text(self._params)).replace(", ", "/")

    def describe(self) -> str:
        p = self._params
        a = p["alpha_x"]
        return (f"CoatedDiffuse R={_sp.fmt_param(p['reflectance'])}, " + (f"α={a:.2g}" if a >= 1e-3 else "smooth")
                + _medium(p) + _method_text(p))


class CoatedConductor(_AnalyticSpectral, BxDF):
    __doc__ = """Metal under a dielectric coating with an optional scattering medium between them
    (car paint, lacquered metal): pbrt-v4's ``CoatedConductorBxDF``
    (``LayeredBxDF<DielectricBxDF, ConductorBxDF, true>``).

    ``from_metal(name, ...)`` takes eta, k from ``bsdfkit.METALS``; ``from_reflectance(r, ...)``
    uses pbrt-v4's artist mapping eta = 1, k = 2 sqrt(r) / sqrt(1 - r) (r clamped to 0.9999),
    also divided by ``interface_eta`` (pbrt-v4 does the same).

    Parameters
    ----------
    conductor_eta, conductor_k : RGB or Spectrum
        The metal's complex IOR per RGB channel, relative to vacuum (eta > 0, k >= 0). As in
        pbrt-v4 (since PR #343, issue #342), the base sees the metal *relative to the coating*:
        both are divided by ``interface_eta`` before use, so a coated metal is darker and less
        tinted at normal incidence than the bare metal.
    conductor_alpha, conductor_alpha_x, conductor_alpha_y : float, optional
        GGX alpha of the metal (isotropic, or per tangent axis).
    interface_eta : float, optional
        Relative IOR of the coating (> 0).
    interface_alpha, interface_alpha_x, interface_alpha_y : float, optional
        GGX alpha of the coating.
    masking : {"correlated", "separable"}, optional
        Masking-shadowing of both microfacet interfaces.""" + _LAYER_PARAMS + """
    Examples
    --------
    >>> import bsdfkit as bk
    >>> m = bk.CoatedConductor.from_metal("Cu", conductor_alpha=0.3, interface_alpha=0.02, method="analytic")
    >>> m.albedo(bk.direction(0.5, 0.0), n_samples=1024).shape
    (3,)
    """ + _LAYER_DOC

    __slots__ = ()

    aliases = ("carpaint",)
    examples = {"car paint": "coated_conductor metal=Cu conductor_alpha=0.3 interface_alpha=0.02 albedo=0.5,0.1,0.1 "
                             "thickness=0.1",
                "car paint, analytic": "coated_conductor metal=Cu conductor_alpha=0.3 interface_alpha=0.02 "
                                       "albedo=0.5,0.1,0.1 thickness=0.1 method=analytic",
                "lacquered gold, smooth, analytic": "coated_conductor metal=Au thickness=0.05 method=analytic"}
    description = "metal under a dielectric coat with an optional HG medium (pbrt-v4, stochastic)"
    # bk.fit bounds (gradients: method="analytic" only)
    param_ranges = {"conductor_eta": (1e-3, 10.0), "conductor_k": (0.0, 20.0), "conductor_alpha_x": (1e-3, 2.0),
                    "conductor_alpha_y": (1e-3, 2.0), "interface_eta": (1.001, 4.0), "interface_alpha_x": (1e-3, 2.0),
                    "interface_alpha_y": (1e-3, 2.0), "thickness": (0.0, 10.0), "albedo": (0.0, 1.0), "g": (-0.99, 0.99)}
    varying_params = {"conductor_eta": 3, "conductor_k": 3, "conductor_alpha_x": 1, "conductor_alpha_y": 1,
                      "interface_eta": 1, "interface_alpha_x": 1, "interface_alpha_y": 1, "thickness": 1, "albedo": 3,
                      "g": 1}
    energy_conserving, two_sided, transmission, delta_only = True, True, False, False
    exact_eval, reciprocal = _ByMethod(False, True), _ByMethod(False, True)   # per instance: see _ByMethod
    mitsuba = None
    knobs = _KNOBS

    def to_mitsuba(self, approximate: bool = False) -> dict:
        """Raises NotImplementedError: Mitsuba 3 has no plugin for pbrt-v4's stochastic layered
        BSDFs (its ``plastic`` is a different, closed-form coating model: ``bsdfkit.Plastic``)."""
        from ._mitsuba_export import no_plugin
        no_plugin(self, approximate, "Mitsuba 3 has no plugin for pbrt-v4's layered (coated) BSDFs; "
                  "bsdfkit.Plastic is the coating model Mitsuba has (plastic / roughplastic)")

    def __init__(self, conductor_eta, conductor_k, conductor_alpha=0.0, conductor_alpha_x=None,
                 conductor_alpha_y=None, interface_eta=1.5, interface_alpha=0.0, interface_alpha_x=None,
                 interface_alpha_y=None, thickness=0.01, albedo=0.0, g=0.0, max_depth=10, n_samples=1, seed=0,
                 masking="correlated", mis="pbrt", method="stochastic"):
        """A CoatedConductor: the parameters are described in the class docstring (``help(bsdfkit.CoatedConductor)``);
        a bad value raises ValueError (TypeError for a wrong type) naming the parameter."""
        cax, cay = _named_alphas(conductor_alpha, conductor_alpha_x, conductor_alpha_y, "conductor_alpha")
        iax, iay = _named_alphas(interface_alpha, interface_alpha_x, interface_alpha_y, "interface_alpha")
        super().__init__(conductor_eta=_sp.spectrum_or_rgb(conductor_eta, "conductor_eta", lo=0.0, lo_open=True,
                                                           varying=True),
                         conductor_k=_sp.spectrum_or_rgb(conductor_k, "conductor_k", lo=0.0, varying=True),
                         conductor_alpha_x=cax, conductor_alpha_y=cay,
                         interface_eta=_scalar(interface_eta, "interface_eta", lo=0.0, lo_open=True, varying=True),
                         interface_alpha_x=iax, interface_alpha_y=iay,
                         **_layer(thickness, albedo, g, max_depth, n_samples, seed, mis, method),
                         masking=_masking(masking))

    @classmethod
    def _from_params(cls, p):
        return cls(**p)

    @classmethod
    def from_metal(cls, metal: str, conductor_roughness=None, **kwargs) -> "CoatedConductor":
        """A measured metal by name (``bsdfkit.METALS``) under the coating; ``conductor_roughness``
        is pbrt's remapped roughness (alpha = sqrt(r)), or pass ``conductor_alpha``."""
        if metal not in METALS:
            raise ValueError(f"metal: unknown metal {metal!r}; known metals: {', '.join(sorted(METALS))}")
        eta, k = METALS[metal]
        if conductor_roughness is not None:
            kwargs["conductor_alpha"] = _pick_alpha(conductor_roughness, kwargs.pop("conductor_alpha", None))
        return cls(eta, k, **kwargs)

    @classmethod
    def from_reflectance(cls, reflectance, **kwargs) -> "CoatedConductor":
        """pbrt-v4's artist form: eta = 1, k = 2 sqrt(r) / sqrt(1 - r), r in [0, 1] clamped to 0.9999
        (then divided by interface_eta like any conductor IOR)."""
        r = np.minimum(_rgb(reflectance, "reflectance", lo=0.0, hi=1.0), 0.9999)
        return cls(1.0, 2 * np.sqrt(r) / np.sqrt(1 - r), **kwargs)

    def _make_core(self):
        p = self._params
        core = _core.CoatedConductorAnalytic if p["method"] == "analytic" else _core.CoatedConductor
        return core(**self._core_kwargs())

    def _core_kwargs(self) -> dict:
        p = self._params
        return dict(conductor_eta=core_value(_sp.rgb_of(p["conductor_eta"], "unbounded")),
                    conductor_k=core_value(_sp.rgb_of(p["conductor_k"], "unbounded")),
                    conductor_alpha_x=p["conductor_alpha_x"], conductor_alpha_y=p["conductor_alpha_y"],
                    interface_eta=p["interface_eta"], interface_alpha_x=p["interface_alpha_x"],
                    interface_alpha_y=p["interface_alpha_y"], masking=_MASKING[p["masking"]], **_layer_kw(p))

    def _spectral_inputs(self) -> dict:
        return {} if self._params["method"] == "analytic" else {"has_albedo": self._has_medium()}

    @staticmethod
    def relative_cost(params, dtype=None) -> float:
        """Relative cost of a configuration (the tuning registry's cost model; see _relative_cost)."""
        return _relative_cost(params, dtype)

    def cost_family(self) -> str:
        return "CoatedConductor" + (_medium(self._params) + _method_text(self._params)).replace(", ", "/")

    def describe(self) -> str:
        if self.varying:
            return BxDF.describe(self)
        p = self._params
        spectral = isinstance(p["conductor_eta"], Spectrum) or isinstance(p["conductor_k"], Spectrum)
        name = None if spectral else next((n for n, (eta, k) in METALS.items()
                                           if np.allclose(p["conductor_eta"], eta) and np.allclose(p["conductor_k"], k)),
                                          None)
        name = name or f"η={_sp.fmt_param(p['conductor_eta'])}"
        return (f"CoatedConductor {name}, α={p['conductor_alpha_x']:.2g}/{p['interface_alpha_x']:.2g}{_medium(p)}"
                f"{_method_text(p)}")


def _named_alphas(alpha, ax, ay, name):
    a = _scalar(alpha, name, lo=0.0, varying=True)
    x = a if ax is None else _scalar(ax, name + "_x", lo=0.0, varying=True)
    y = a if ay is None else _scalar(ay, name + "_y", lo=0.0, varying=True)
    return x, y
