"""The models: the base class and registry (``base``), then one module per family.

``diffuse`` (Diffuse, DiffuseTransmission), ``conductor`` (Conductor, METALS, conductor_fresnel),
``dielectric`` (Dielectric, ThinDielectric), ``filament`` (FilamentStandard, FilamentCloth, the
DFG table). A new family is a new module here whose classes subclass :class:`BxDF`.
"""
from .base import BxDF, SampleResult, roughness_to_alpha
from .conductor import METALS, Conductor, conductor_fresnel
from .dielectric import Dielectric, ThinDielectric
from .diffuse import Diffuse, DiffuseTransmission
from .filament import FilamentCloth, FilamentStandard
from .layered import CoatedConductor, CoatedDiffuse
from .plastic import Plastic

__all__ = ["BxDF", "SampleResult", "roughness_to_alpha", "METALS", "Conductor", "conductor_fresnel", "Dielectric",
           "ThinDielectric", "Diffuse", "DiffuseTransmission", "FilamentStandard", "FilamentCloth", "MODELS",
           "Plastic", "CoatedDiffuse", "CoatedConductor"]

#: Every model class, in gallery order.
MODELS = (Diffuse, DiffuseTransmission, Conductor, Dielectric, ThinDielectric, FilamentStandard, FilamentCloth,
          Plastic, CoatedDiffuse, CoatedConductor)
