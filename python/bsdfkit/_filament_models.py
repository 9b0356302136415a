"""Deprecated: the Filament models live in :mod:`bsdfkit.models.filament`."""
from ._deprecated import warn
from .models.filament.materials import FilamentCloth, FilamentStandard  # noqa: F401

warn("bsdfkit._filament_models", "bsdfkit.models.filament")
