"""The optional compiled part, ``bsdfkit._render``: the preview renderer, image I/O and mesh files
(it links Embree 3, OpenImageIO and Assimp). ``bsdfkit._core`` (the models) never needs it; it is
imported on the first call that does (``bk.render``, ``bk.io``), so ``import bsdfkit`` does not
load those libraries."""
from __future__ import annotations

import importlib

__all__ = ["load", "available"]

_mod = None

_HOW = ("install Embree 3 and OpenImageIO (Debian/Ubuntu: apt-get install libembree-dev libopenimageio-dev; "
        "libassimp-dev for mesh files), then reinstall bsdfkit from source (pip install .)")


def load():
    """The ``bsdfkit._render`` extension module, imported on first use. Raises ImportError naming
    what to install when this build of bsdfkit has none, or when a library it links is missing."""
    global _mod
    if _mod is None:
        try:
            _mod = importlib.import_module("bsdfkit._render")
        except ModuleNotFoundError as e:
            if e.name != "bsdfkit._render":
                raise
            raise ImportError(
                "bsdfkit.render and bsdfkit.io need the optional extension bsdfkit._render, which this build "
                f"of bsdfkit does not have (it was built without Embree 3 / OpenImageIO): {_HOW}",
                name="bsdfkit._render") from None
        except ImportError as e:
            raise ImportError(
                f"bsdfkit._render (renderer and image I/O) cannot be loaded: {e}. A library it links is missing: "
                f"{_HOW}", name="bsdfkit._render") from e
    return _mod


def available() -> bool:
    """Whether the renderer and image I/O can be used (imports ``bsdfkit._render`` if needed)."""
    try:
        load()
    except ImportError:
        return False
    return True
