"""Filament's material models as bsdfkit models (C++ core: cpp/include/bsdfkit/bxdfs/filament.h)."""
from __future__ import annotations

import numbers

import numpy as np

from ... import _core
from . import dfg as _fil
from .. import _spectral as _sp
from ..base import BxDF, _scalar, core_value
from ..registry import KnobDecl

__all__ = ["FilamentStandard", "FilamentCloth", "examples"]

_DIFFUSE = {"lambert": 0, "burley": 1}
_VISIBILITY = {"correlated": 0, "fast": 1}
_F90 = {"one": False, "filament": True}
_LAYERING = {"code": 0, "doc": 1}
#: Lower bound of a numeric ``min_roughness``: alpha = r**2 must stay above the effectively-smooth
#: threshold 1e-3 of the shared GGX code (Filament's models have no delta lobe).
MIN_ROUGHNESS_FLOOR = 0.0317


def _choice(value, name, table):
    if not isinstance(value, str) or value not in table:
        raise ValueError(f"{name}: must be one of {', '.join(repr(k) for k in table)}, got {value!r}")
    return value


def _flag(value, name):
    if not isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{name}: must be True or False, got {value!r}")
    return bool(value)


def _min_roughness(value):
    if isinstance(value, str):
        return _choice(value, "min_roughness", _fil.MIN_PERCEPTUAL_ROUGHNESS)
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ValueError(f"min_roughness: must be 'desktop', 'mobile' or a perceptual roughness, got {value!r}")
    return _scalar(value, "min_roughness", lo=MIN_ROUGHNESS_FLOOR, hi=1.0)


def _min_pr(value) -> float:
    return _fil.MIN_PERCEPTUAL_ROUGHNESS[value] if isinstance(value, str) else float(value)


def _lut_size(value):
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not 2 <= value <= 4096:
        raise ValueError(f"dfg_lut_size: must be an integer in [2, 4096], got {value!r}")
    return int(value)


# ---------------------------------------------------------------- knob declarations (read by bsdfkit.tuning)

def _proj(v):
    """A colour parameter in RGB: as given, or a ``bsdfkit.Spectrum`` projected to linear sRGB (D65)."""
    return _sp.rgb_of(v, "reflectance")


def _f0(q) -> np.ndarray:
    """Per-channel f0 of a FilamentStandard parameter set (computeF0 + CLEAR_COAT_IOR_CHANGE)."""
    f0 = _proj(q["base_color"]) * q["metallic"] + 0.16 * q["reflectance"] ** 2 * (1 - q["metallic"])
    if q["clear_coat_ior_change"] and q["clear_coat"] > 0:
        cc = q["clear_coat"]
        f0 = f0 + cc * (_fil.term("f0ClearCoatToSurface", f0) - f0)
    return f0


def _strength(v) -> float:
    return float(np.max(_proj(v)))


def _lobe_settings(param):
    """keep (the input's strength) then drop (0), or only keep when the lobe is absent."""
    def settings(q):
        v = q[param]
        zero = np.zeros(3) if isinstance(v, np.ndarray) else 0.0
        return (v, zero) if _strength(v) > 0 else (v,)
    return settings


def _lobe_labels(param):
    return lambda q: ("keep", "drop") if _strength(q[param]) > 0 else ("keep",)


def _diffuse_moot(q):
    return ("no diffuse colour (base_color (1 - metallic) = 0)"
            if float(np.max(_proj(q["base_color"]) * (1 - q["metallic"]))) == 0 else None)


def _visibility_moot(q):
    return "anisotropic lobe: always V_SmithGGXCorrelated_Anisotropic" if q["anisotropy"] != 0 else None


def _f90_moot(q):
    return ("the f90 rule saturates (16.5 sum(f0) >= 1): f90 = 1 either way"
            if 16.5 * float(np.sum(_f0(q))) >= 1.0 else None)


def _ec_moot(q):
    return "f0 = 0: the compensation 1 + f0 (1/DFG.y - 1) is 1" if float(np.max(_f0(q))) == 0 else None


def _lut_moot(q):
    ec_on = q["energy_compensation"] and _ec_moot(q) is None
    if not ec_on and _strength(q["sheen_color"]) == 0:
        return "without energy compensation and sheen, the DFG table only feeds sampling probabilities"
    return None


def _lut_settings(q) -> tuple:
    """DFG table sizes, largest (most accurate) first: 128, 64, 32, 16 and the input's own size."""
    return tuple(sorted({128, 64, 32, 16, int(q["dfg_lut_size"])}, reverse=True))


class FilamentStandard(BxDF):
    """Filament's standard material: Lambert (or Burley) diffuse + GGX specular with Schlick
    Fresnel, optional anisotropy, clear coat and sheen, and multiple-scattering energy
    compensation (Filament ``surface_shading_model_standard.fs``; doc "Standard model").

    f0 = 0.16 reflectance**2 (1 - metallic) + base_color metallic and the diffuse color is
    base_color (1 - metallic). The keyword-only knobs' defaults reproduce Filament's desktop,
    FILAMENT_QUALITY_HIGH shading.

    Parameters
    ----------
    base_color : float or RGB or Spectrum, optional
        RGB in [0, 1] (linear).
    metallic : float, optional
        In [0, 1].
    roughness : float, optional
        *Perceptual* roughness in [0, 1] (GGX alpha = roughness**2, clamped below by
        ``min_roughness``).
    reflectance : float, optional
        In [0, 1]: dielectric f0 = 0.16 reflectance**2.
    anisotropy : float, optional
        In [-1, 1]; alpha_t = alpha (1 + a) along local x, alpha_b = alpha (1 - a) along y.
    clear_coat, clear_coat_roughness : float, optional
        In [0, 1]; an isotropic IOR 1.5 (f0 = 0.04) GGX coat with Kelemen visibility; it raises
        the base roughness to mix(r, max(r, r_coat), clear_coat).
    sheen_color : float or RGB or Spectrum, optional
        RGB in [0, 1]: a Charlie sheen lobe; the base below is scaled by 1 - max(sheen_color)
        DFG.z (KHR_materials_sheen as in Filament), floored at 0 (DFG.z, the sheen albedo,
        exceeds 1 at grazing angles for sheen roughness below ~0.1, where Filament's factor
        turns negative).
    sheen_roughness : float, optional
        In [0, 1].
    diffuse : {"lambert", "burley"}, optional
        ``Fd_Lambert`` (Filament's BRDF_DIFFUSE) or ``Fd_Burley``.
    visibility : {"correlated", "fast"}, optional
        ``V_SmithGGXCorrelated`` or ``V_SmithGGXCorrelated_Fast`` (Filament's quality < HIGH).
        Anisotropic lobes always use ``V_SmithGGXCorrelated_Anisotropic``, as in Filament.
    f90 : {"filament", "one"}, optional
        f90 = saturate(16.5 (f0.r + f0.g + f0.b)), the default-quality "specular occlusion", or
        f90 = 1 (LOW quality).
    energy_compensation : bool, optional
        True multiplies the specular lobe by 1 + f0 (1/DFG.y - 1) (Kulla-Conty as simplified by
        Lagarde; the diffuse lobe is not reduced, as in Filament).
    min_roughness : {"desktop", "mobile"} or float, optional
        Perceptual 0.045, 0.089, or a number in [0.0317, 1]: the MIN_PERCEPTUAL_ROUGHNESS clamp
        applied to every roughness (the anisotropic alphas are floored at its square,
        MIN_ROUGHNESS).
    clear_coat_layering : {"code", "doc"}, optional
        (Fd + Fr) (1 - Fc) + Frc (Filament's shaders) or (Fd + Fr (1 - Fc)) (1 - Fc) + Frc
        (Filament's document: specular attenuated twice).
    clear_coat_ior_change : bool, optional
        True (Filament's default) re-derives the base f0 under an IOR 1.5 coat:
        f0 <- mix(f0, f0ClearCoatToSurface(f0), clear_coat).
    dfg_lut_size : int, optional
        Side of the DFG table (``bsdfkit.filament.dfg_lut``), default 128.

    Raises
    ------
    ValueError
        A value out of its range, naming the parameter (TypeError for a wrong type).

    Examples
    --------
    >>> import bsdfkit as bk
    >>> m = bk.FilamentStandard(base_color=[0.8, 0.1, 0.1], roughness=0.4, clear_coat=1.0)
    >>> m.eval(bk.direction(0.5, 0.0), bk.direction(0.5, 3.14159)).shape
    (3,)

    Notes
    -----
    One-sided, as in Filament: f and pdf are 0 unless both wo and wi are above the surface
    (z > 0). eval excludes the cosine (Filament's shading is f <NoL>). NoV is clamped to 1e-4
    where Filament clamps it. Not reciprocal in general (energy compensation and sheen scaling
    depend on wo only) and not energy conserving (Filament does not reduce the diffuse lobe by
    the specular albedo). Sampling: lobes chosen by their estimated albedo at wo; visible-normal
    sampling for the GGX lobes, cosine for diffuse, Charlie-NDF/cosine mixture for sheen.

    Spectral mode (``wavelengths=``): ``base_color`` and ``sheen_color`` may be ``bsdfkit.Spectrum``
    values (RGB ones are uplifted, Jakob & Hanika 2019, bounded); f0 and the diffuse colour are
    computed per wavelength as per RGB channel. What Filament defines on the RGB triple stays
    wavelength-independent, from the RGB projection (linear sRGB, D65): f90 = saturate(16.5
    sum(f0)), the lobe-selection weights (so pdf has one value per element, the RGB model's) and
    max(sheen_color) of the sheen scaling. RGB mode uses the projection.

    Not reproduced from the shaders: their fp16 overflow guards (D_GGX's cap k <= 453.5, which
    lowers the highlight peak by up to 16 % below perceptual roughness 0.047; the mobile-only
    visibility floors). The DFG table is bsdfkit's own float64 integration (``bsdfkit.filament``).
    """

    __slots__ = ()

    description = "Filament's standard material: diffuse + GGX specular, clear coat, sheen, anisotropy"
    examples = {
        "plastic (defaults)": "filament_standard 0.8,0.5,0.3",
        "plastic, Burley diffuse": "filament_standard 0.8,0.5,0.3 diffuse=burley",
        "plastic, low quality (fast V, f90 1, no EC, mobile)":
            "filament_standard 0.8,0.5,0.3 visibility=fast f90=one energy_compensation=false min_roughness=mobile",
        "gold, rough": "filament_standard 1,0.85,0.57 metallic=1 roughness=0.6",
        "gold, rough, no energy compensation":
            "filament_standard 1,0.85,0.57 metallic=1 roughness=0.6 energy_compensation=false",
        "brushed aluminium (anisotropy 0.8)": "filament_standard 0.91,0.92,0.92 metallic=1 roughness=0.5 anisotropy=0.8",
        "car paint (clear coat over blue metal)":
            "filament_standard 0.05,0.2,0.7 metallic=0.7 roughness=0.5 clear_coat=1 clear_coat_roughness=0.05",
        "car paint, doc layering": "filament_standard 0.05,0.2,0.7 metallic=0.7 roughness=0.5 clear_coat=1 "
                                   "clear_coat_roughness=0.05 clear_coat_layering=doc",
        "satin (sheen)": "filament_standard 0.3,0.05,0.1 roughness=0.6 sheen_color=0.9,0.6,0.7 sheen_roughness=0.4",
        "faint clear coat (README)": "filament_standard clear_coat=0.001",
        "coated satin, reflectance 0.1 (every knob reachable)":
            "filament_standard 0.8,0.5,0.3 reflectance=0.1 clear_coat=0.5 clear_coat_roughness=0.1 "
            "sheen_color=0.6,0.5,0.4 sheen_roughness=0.5",
        "plastic, reflectance 0.1": "filament_standard 0.8,0.5,0.3 reflectance=0.1",
    }
    energy_conserving, exact_eval, two_sided, transmission, delta_only = False, True, False, False, False
    reciprocal = False  # energy compensation and sheen scaling depend on wo only
    mitsuba = None
    varying_params = {"base_color": 3, "metallic": 1, "roughness": 1, "reflectance": 1, "anisotropy": 1,
                      "clear_coat": 1, "clear_coat_roughness": 1, "sheen_color": 3, "sheen_roughness": 1}
    param_ranges = {"base_color": (0.0, 1.0), "metallic": (0.0, 1.0), "roughness": (0.0, 1.0),  # bk.fit bounds
                    "reflectance": (0.0, 1.0), "anisotropy": (-1.0, 1.0), "clear_coat": (0.0, 1.0),
                    "clear_coat_roughness": (0.0, 1.0), "sheen_color": (0.0, 1.0), "sheen_roughness": (0.0, 1.0)}
    knobs = (
        KnobDecl("clear_coat", _lobe_settings("clear_coat"), "approximation",
                 "clear-coat lobe: keep, or drop (clear_coat = 0, compiled variant without the coat)",
                 labels=_lobe_labels("clear_coat"), lobe=True),
        KnobDecl("sheen", _lobe_settings("sheen_color"), "approximation",
                 "sheen lobe: keep, or drop (sheen_color = 0, compiled variant without sheen)",
                 param="sheen_color", labels=_lobe_labels("sheen_color"), lobe=True),
        KnobDecl("diffuse", ("burley", "lambert"), "modelling",
                 "diffuse term: Fd_Burley (retro-reflection, grazing falloff) or Fd_Lambert", moot=_diffuse_moot),
        KnobDecl("visibility", ("correlated", "fast"), "approximation",
                 "V_SmithGGXCorrelated or its _Fast approximation (Hammon 2017)", moot=_visibility_moot),
        KnobDecl("f90", ("filament", "one"), "modelling",
                 "Schlick f90: the specular-occlusion rule saturate(16.5 sum f0), or 1", moot=_f90_moot),
        KnobDecl("energy_compensation", (True, False), "modelling",
                 "multiple-scattering energy compensation 1 + f0 (1/DFG.y - 1)", moot=_ec_moot),
        KnobDecl("dfg_lut_size", _lut_settings, "approximation",
                 "side of the DFG table (energy compensation, sheen scaling)", moot=_lut_moot),
    )

    def __init__(self, base_color=0.8, metallic=0.0, roughness=0.5, reflectance=0.5, anisotropy=0.0,
                 clear_coat=0.0, clear_coat_roughness=0.0, sheen_color=0.0, sheen_roughness=0.0, *,
                 diffuse="lambert", visibility="correlated", f90="filament", energy_compensation=True,
                 min_roughness="desktop", clear_coat_layering="code", clear_coat_ior_change=True,
                 dfg_lut_size=128):
        super().__init__(
            base_color=_sp.spectrum_or_rgb(base_color, "base_color", lo=0.0, hi=1.0, varying=True),
            metallic=_scalar(metallic, "metallic", lo=0.0, hi=1.0, varying=True),
            roughness=_scalar(roughness, "roughness", lo=0.0, hi=1.0, varying=True),
            reflectance=_scalar(reflectance, "reflectance", lo=0.0, hi=1.0, varying=True),
            anisotropy=_scalar(anisotropy, "anisotropy", lo=-1.0, hi=1.0, varying=True),
            clear_coat=_scalar(clear_coat, "clear_coat", lo=0.0, hi=1.0, varying=True),
            clear_coat_roughness=_scalar(clear_coat_roughness, "clear_coat_roughness", lo=0.0, hi=1.0, varying=True),
            sheen_color=_sp.spectrum_or_rgb(sheen_color, "sheen_color", lo=0.0, hi=1.0, varying=True),
            sheen_roughness=_scalar(sheen_roughness, "sheen_roughness", lo=0.0, hi=1.0, varying=True),
            diffuse=_choice(diffuse, "diffuse", _DIFFUSE),
            visibility=_choice(visibility, "visibility", _VISIBILITY),
            f90=_choice(f90, "f90", _F90),
            energy_compensation=_flag(energy_compensation, "energy_compensation"),
            min_roughness=_min_roughness(min_roughness),
            clear_coat_layering=_choice(clear_coat_layering, "clear_coat_layering", _LAYERING),
            clear_coat_ior_change=_flag(clear_coat_ior_change, "clear_coat_ior_change"),
            dfg_lut_size=_lut_size(dfg_lut_size))

    @classmethod
    def _from_params(cls, p):
        return cls(**p)

    def describe(self) -> str:
        p = self._params
        spectral = [k for k in ("base_color", "sheen_color") if isinstance(p[k], _sp.Spectrum)]
        if not spectral:
            return super().describe()
        q = dict(p, **{k: _proj(p[k]) for k in spectral})   # the spec text of the RGB projection
        return type(self)._from_params(q).describe() + f" ({', '.join(spectral)} spectral)"

    def cost_family(self) -> str:
        p = self._params
        lobes = [x for x, on in (("coat", np.any(p["clear_coat"] > 0)), ("sheen", _strength(p["sheen_color"]) > 0)) if on]
        return "FilamentStandard" + ("/" + "+".join(lobes) if lobes else "")

    @property
    def min_perceptual_roughness(self) -> float:
        """The MIN_PERCEPTUAL_ROUGHNESS value in effect."""
        return _min_pr(self._params["min_roughness"])

    def _make_core(self):
        # Four compiled variants, with or without the clear-coat and the sheen lobes (absent lobes
        # cost nothing; the sheen lobe's pow() keeps a kernel scalar); each equals the general
        # model with the missing lobe's strength 0.
        p = self._params
        # (per-element parameters: the variant with every lobe any element has)
        return self._core_variant(bool(np.any(p["clear_coat"] > 0)), _strength(p["sheen_color"]) > 0)

    def _grad_core(self, params):
        """``eval_grad``'s kernel: the model's own variant, or the one with the clear-coat / sheen
        lobe when a parameter of that lobe is differentiated (at strength 0 the lobe's value is 0
        but its derivative is not). ``params`` as ``eval_grad`` (None: every parameter)."""
        p = self._params
        names = ("clear_coat", "sheen_color") if params is None else (params,) if isinstance(params, str) else params
        names = [str(n).partition(".")[0] for n in names]
        coat = bool(np.any(p["clear_coat"] > 0)) or any(n.startswith("clear_coat") for n in names)
        sheen = _strength(p["sheen_color"]) > 0 or any(n.startswith("sheen") for n in names)
        return self._core if (coat, sheen) == self._core_variant_key() else self._core_variant(coat, sheen)

    def _core_variant_key(self):
        p = self._params
        return bool(np.any(p["clear_coat"] > 0)), _strength(p["sheen_color"]) > 0

    def _core_variant(self, coat, sheen):
        p = self._params
        cls = {(False, False): _core.FilamentStandard, (True, False): _core.FilamentStandardCoat,
               (False, True): _core.FilamentStandardSheen, (True, True): _core.FilamentStandardCoatSheen}[coat, sheen]
        return cls(**self._core_kwargs())

    def _core_kwargs(self) -> dict:
        p = self._params
        return dict(base_color=core_value(_proj(p["base_color"])), metallic=p["metallic"], roughness=p["roughness"],
                   reflectance=p["reflectance"], anisotropy=p["anisotropy"], clear_coat=p["clear_coat"],
                   clear_coat_roughness=p["clear_coat_roughness"], sheen_color=core_value(_proj(p["sheen_color"])),
                   sheen_roughness=p["sheen_roughness"], diffuse=_DIFFUSE[p["diffuse"]],
                   visibility=_VISIBILITY[p["visibility"]], f90_filament=_F90[p["f90"]],
                   energy_compensation=p["energy_compensation"], min_perceptual_roughness=_min_pr(p["min_roughness"]),
                   layering=_LAYERING[p["clear_coat_layering"]], clear_coat_ior_change=p["clear_coat_ior_change"],
                   dfg=_fil._table(p["dfg_lut_size"]))


class FilamentCloth(BxDF):
    """Filament's cloth material (``surface_shading_model_cloth.fs``; doc "Cloth model").

    Parameters
    ----------
    base_color : float or RGB or Spectrum, optional
        RGB in [0, 1], the diffuse color.
    sheen_color : float or RGB or Spectrum, optional
        RGB in [0, 1], the specular color of the Charlie sheen lobe D_Charlie V_Neubelt
        sheen_color (no Fresnel term); None (default) means sqrt(base_color), Filament's default.
    subsurface_color : float or RGB or Spectrum, optional
        RGB in [0, 1] or None (default, no subsurface): when given, the diffuse lobe becomes
        Filament's wrapped diffuse Fd_Wrap(NoL, 0.5) saturate(subsurface_color + NoL)
        base_color / pi, which Filament does not multiply by NoL -- here it is divided by NoL
        (f <NoL> stays bounded, f grows as 1/NoL at the horizon).
    roughness : float, optional
        Perceptual, [0, 1] (alpha = roughness**2).
    diffuse, min_roughness, dfg_lut_size : optional
        Keyword-only knobs, as for :class:`FilamentStandard`.

    Raises
    ------
    ValueError
        A value out of its range, naming the parameter (TypeError for a wrong type).

    Examples
    --------
    >>> import bsdfkit as bk
    >>> m = bk.FilamentCloth(base_color=[0.6, 0.2, 0.2], roughness=0.7)
    >>> float(m.eval(bk.direction(0.5, 0.0), -bk.direction(0.5, 1.0)).max())   # one-sided
    0.0

    One-sided (f = pdf = 0 unless wo.z > 0 and wi.z > 0); no energy compensation; not energy
    conserving (the diffuse lobe is not reduced by the sheen, as in Filament). Sampling: diffuse
    by cosine (or by a cos(theta) + 0.5 density with a subsurface color), sheen by an equal
    mixture of Charlie-NDF and diffuse-sampler directions; lobes chosen by estimated albedo.

    Spectral mode (``wavelengths=``): ``base_color``, ``sheen_color`` and ``subsurface_color`` may
    be ``bsdfkit.Spectrum`` values in [0, 1] (RGB ones are uplifted, Jakob & Hanika 2019,
    bounded); per wavelength each is what one RGB channel holds, and a missing sheen_color is
    sqrt(base_color(lambda)). The lobe-selection weights (max(base_color), max(sheen_color)) stay
    wavelength-independent, from the RGB projection (linear sRGB, D65), so pdf has one value per
    element, the RGB model's. RGB mode uses the projection.
    """

    __slots__ = ()

    description = "Filament's cloth material: diffuse (optionally wrapped, subsurface) + Charlie sheen"
    examples = {
        "cloth (denim)": "filament_cloth 0.1,0.15,0.35 roughness=0.8",
        "cloth (velvet, subsurface)": "filament_cloth 0.35,0.02,0.08 sheen_color=0.9,0.4,0.5 "
                                      "subsurface_color=0.3,0.05,0.05 roughness=0.35",
        "cloth (defaults)": "filament_cloth",
    }
    energy_conserving, exact_eval, two_sided, transmission, delta_only = False, True, False, False, False
    reciprocal = False  # energy compensation and sheen scaling depend on wo only
    mitsuba = None
    param_ranges = {"base_color": (0.0, 1.0), "sheen_color": (0.0, 1.0), "subsurface_color": (0.0, 1.0),  # bk.fit
                    "roughness": (0.0, 1.0)}
    varying_params = {"base_color": 3, "sheen_color": 3, "subsurface_color": 3, "roughness": 1}
    knobs = (
        KnobDecl("diffuse", ("burley", "lambert"), "modelling", "diffuse term: Fd_Burley or Fd_Lambert",
                 moot=lambda q: "black base colour" if _strength(q["base_color"]) == 0 else None),
        KnobDecl("dfg_lut_size", lambda q: (q["dfg_lut_size"],), "approximation",
                 "side of the DFG table (sampling probabilities only)",
                 moot=lambda q: "the cloth's DFG table only feeds the lobe-selection probabilities of sample/pdf"),
    )

    def __init__(self, base_color=0.5, sheen_color=None, subsurface_color=None, roughness=0.5, *,
                 diffuse="lambert", min_roughness="desktop", dfg_lut_size=128):
        super().__init__(
            base_color=_sp.spectrum_or_rgb(base_color, "base_color", lo=0.0, hi=1.0, varying=True),
            sheen_color=None if sheen_color is None else _sp.spectrum_or_rgb(sheen_color, "sheen_color", lo=0.0, hi=1.0,
                                                                              varying=True),
            subsurface_color=(None if subsurface_color is None
                              else _sp.spectrum_or_rgb(subsurface_color, "subsurface_color", lo=0.0, hi=1.0, varying=True)),
            roughness=_scalar(roughness, "roughness", lo=0.0, hi=1.0, varying=True),
            diffuse=_choice(diffuse, "diffuse", _DIFFUSE),
            min_roughness=_min_roughness(min_roughness),
            dfg_lut_size=_lut_size(dfg_lut_size))

    @classmethod
    def _from_params(cls, p):
        return cls(**p)

    @property
    def effective_sheen_color(self) -> np.ndarray:
        """sheen_color, or sqrt(base_color) when it was not given (RGB; a spectrum's RGB projection)."""
        s = self._params["sheen_color"]
        return np.sqrt(_proj(self._params["base_color"])) if s is None else _proj(s)

    def describe(self) -> str:
        p = self._params
        spectral = [k for k in ("base_color", "sheen_color", "subsurface_color") if isinstance(p[k], _sp.Spectrum)]
        if not spectral:
            return super().describe()
        q = dict(p, **{k: _proj(p[k]) for k in spectral})   # the spec text of the RGB projection
        return type(self)._from_params(q).describe() + f" ({', '.join(spectral)} spectral)"

    @property
    def min_perceptual_roughness(self) -> float:
        """The MIN_PERCEPTUAL_ROUGHNESS value in effect."""
        return _min_pr(self._params["min_roughness"])

    def _core_kwargs(self) -> dict:
        p = self._params
        ss = p["subsurface_color"]
        return dict(base_color=core_value(_proj(p["base_color"])), sheen_color=core_value(self.effective_sheen_color),
                    subsurface_color=[0.0, 0.0, 0.0] if ss is None else core_value(_proj(ss)),
                    has_subsurface=ss is not None, roughness=p["roughness"], diffuse=_DIFFUSE[p["diffuse"]],
                    min_perceptual_roughness=_min_pr(p["min_roughness"]), dfg=_fil._table(p["dfg_lut_size"]))

    def _make_core(self):
        return _core.FilamentCloth(**self._core_kwargs())

    def _spectral_inputs(self) -> dict:
        # FilamentClothSpectral (spectral/hair_spectral.h): a colour not given is 0 and, for the
        # sheen, Filament's sqrt(baseColor) per wavelength (sheen_from_base)
        p = self._params
        sheen, ss = p["sheen_color"], p["subsurface_color"]
        return dict(sheen_color=0.0 if sheen is None else sheen, subsurface_color=0.0 if ss is None else ss,
                    sheen_from_base=sheen is None)

def examples() -> dict:
    """Representative Filament materials by name, one per lobe and knob family (for galleries,
    demos and benchmarks): the registered examples of :class:`FilamentStandard` and
    :class:`FilamentCloth`, built."""
    from ..spec import parse_spec
    return {label: parse_spec(spec) for cls in (FilamentStandard, FilamentCloth) for label, spec in cls.examples.items()}
