"""The models: the base class (``base``), the registry (``registry``), then one module per family.

``diffuse`` (Diffuse, DiffuseTransmission), ``eon`` (EON: energy-preserving Oren-Nayar), ``conductor``
(Conductor, METALS, conductor_fresnel),
``dielectric`` (Dielectric, ThinDielectric), ``filament`` (FilamentStandard, FilamentCloth, the
DFG table), ``measured`` (MERL, Measured: measured tables and tensor files), ``plastic`` (Plastic),
``layered`` (CoatedDiffuse, CoatedConductor), ``normalized_fresnel`` (NormalizedFresnel, fresnel_moment1),
``hair`` (Hair and its sigma_a helpers), ``principled`` (Principled, PrincipledThin: Mitsuba 3's Disney BSDFs), ``openpbr`` (OpenPBR Surface), ``composite`` (Mix, TwoSided, Mask), ``normal_map``
(NormalMap) and ``bump_map`` (BumpMap, height_gradient): models built from other models, in Python. A new family is a new module here whose classes subclass :class:`BxDF`.
"""
from . import registry
from .base import BxDF, SampleResult, roughness_to_alpha
# families in registration (= gallery) order; a new family adds one line here
from .diffuse import Diffuse, DiffuseTransmission  # noqa: I001
from .eon import EON
from .conductor import METALS, Conductor, conductor_fresnel
from .dielectric import Dielectric, ThinDielectric
from .filament import FilamentCloth, FilamentStandard
from .measured import MERL, Measured
from .plastic import Plastic
from .layered import CoatedConductor, CoatedDiffuse
from .normalized_fresnel import NormalizedFresnel
from .hair import Hair
from .principled import Principled, PrincipledThin
from .openpbr import OpenPBR
from .composite import Mask, Mix, TwoSided
from .normal_map import NormalMap
from .bump_map import BumpMap
from .registry import MODELS, KnobDecl

__all__ = ["BxDF", "SampleResult", "roughness_to_alpha", "METALS", "Conductor", "conductor_fresnel", "Dielectric",
           "ThinDielectric", "Diffuse", "DiffuseTransmission", "EON", "FilamentStandard", "FilamentCloth", "MERL", "Measured",
           "Plastic", "CoatedDiffuse", "CoatedConductor", "NormalizedFresnel", "Hair", "Principled", "PrincipledThin", "OpenPBR", "Mix", "TwoSided", "Mask", "NormalMap", "BumpMap", "MODELS", "KnobDecl"]
