"""Scene materials in (one module per source: ``mitsuba``, ``pbrt``, ``gltf``, ``materialx``; ``spectra`` for spectral data): Mitsuba 3 plugin dictionaries, pbrt-v4 scene text, glTF 2.0 and MaterialX materials as bsdfkit models.

* :func:`from_mitsuba` turns a Mitsuba 3 BSDF dictionary (what ``mi.load_dict`` takes) into a
  model, ``bitmap`` textures into ``bk.Texture`` values; it inverts
  :func:`bsdfkit.testing.mitsuba.to_mitsuba`. Given a scene file (``.xml``) it returns
  ``{id: model}``; :func:`to_mitsuba_file` writes one.
* :func:`from_pbrt` reads the ``Material`` / ``MakeNamedMaterial`` statements of pbrt-v4 scene
  text; :func:`parse_pbrt_materials` gives the parsed statements (type, parameters, line, how
  many shapes use them) without converting them.
* :func:`from_gltf` reads the materials of a glTF 2.0 file (``.gltf`` or ``.glb``) as
  ``FilamentStandard`` models (with ``NormalMap`` / ``Mask`` / ``TwoSided`` where asked for);
  :func:`read_gltf_materials` also gives what each leaves out (occlusion, emission, ...).
* :func:`from_materialx` reads the ``gltf_pbr`` and ``UsdPreviewSurface`` materials of a MaterialX
  document (``.mtlx`` or text) as ``FilamentStandard`` models, ``open_pbr_surface`` and
  ``standard_surface`` (through MaterialX's translation graph) as ``OpenPBR``, with ``image`` /
  ``tiledimage`` nodes as textures; it needs the optional ``materialx`` package.
* ``model.to_mitsuba()`` is the other direction: it exports only a model Mitsuba has exactly and
  otherwise raises :class:`MitsubaExportError` naming the reason (e.g. height-correlated masking)
  and the measured difference; ``to_mitsuba(approximate=True)`` exports the nearest Mitsuba
  material and warns with :class:`MitsubaApproximationWarning`.
* :func:`spectrum_to_rgb` projects a wavelength/value spectrum to linear sRGB the way Mitsuba's
  RGB variants do, so spectra in either format give the RGB values Mitsuba would use.

Only what bsdfkit can represent exactly is accepted; everything else (Mitsuba's procedural
textures but its checkerboard, layered materials, Beckmann roughness, ``specular_reflectance``
tints ...) is refused with a ``ValueError`` that names the plugin or material, the parameter and
what is supported.
"""

from ..models._mitsuba_export import MitsubaApproximationWarning, MitsubaExportError
from ._mitsuba_xml import to_mitsuba_file
from .gltf import GLTF_SUPPORTED_EXTENSIONS, GltfMaterial, GltfWarning, from_gltf, read_gltf_materials
from .materialx import MATERIALX_SHADING_MODELS, MaterialXWarning, from_materialx
from .mitsuba import MIRROR_ETA, MITSUBA_IOR, MitsubaSkipWarning, from_mitsuba
from .pbrt import (PBRT_GLASS_ETA, PbrtColorSpaceWarning, PbrtMaterial, PbrtMissingIncludeWarning, PbrtParam,
                   PbrtSkipWarning, from_pbrt, parse_pbrt_materials)
from .spectra import spectrum_to_rgb

__all__ = ["from_mitsuba", "to_mitsuba_file", "MitsubaSkipWarning", "from_pbrt", "from_gltf", "read_gltf_materials",
           "GltfMaterial", "GltfWarning", "GLTF_SUPPORTED_EXTENSIONS", "from_materialx", "MaterialXWarning",
           "MATERIALX_SHADING_MODELS", "parse_pbrt_materials", "PbrtMaterial",
           "PbrtParam", "spectrum_to_rgb", "MITSUBA_IOR", "PBRT_GLASS_ETA", "MIRROR_ETA", "MitsubaExportError",
           "MitsubaApproximationWarning", "PbrtSkipWarning", "PbrtMissingIncludeWarning", "PbrtColorSpaceWarning"]
