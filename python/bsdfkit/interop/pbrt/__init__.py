"""pbrt-v4 scene text -> bsdfkit models: the ``Material`` / ``MakeNamedMaterial`` statements and the
``Texture`` statements they use (``from_pbrt``, ``parse_pbrt_materials``).

Modules: ``parser`` (tokens, statements, Include / Import, the parsed records), ``values``
(parameter values: rgb, spectra, eta), ``textures`` (``Texture`` statements -> bsdfkit textures),
``materials`` (material types -> models, ``from_pbrt``) and ``mix`` (pbrt-v4 ``mix`` materials).
"""
from __future__ import annotations

from .materials import from_pbrt
from .parser import (PBRT_MAX_INCLUDE_DEPTH, PBRT_MAX_INCLUDES, PbrtColorSpaceWarning, PbrtMaterial,
                     PbrtMissingIncludeWarning, PbrtParam, PbrtSkipWarning, PbrtTexture, parse_pbrt_materials)
from .textures import PBRT_TEXTURE_CLASSES, PbrtLookup
from .values import PBRT_GLASS_ETA

__all__ = ["PBRT_GLASS_ETA", "PbrtParam", "PbrtMaterial", "PbrtTexture", "PbrtSkipWarning", "PbrtMissingIncludeWarning",
           "PbrtColorSpaceWarning", "PbrtLookup", "PBRT_TEXTURE_CLASSES", "parse_pbrt_materials", "from_pbrt"]
