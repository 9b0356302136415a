"""Old module paths kept for one release: each shim warns once on import and re-exports."""
from __future__ import annotations

import warnings


def warn(old: str, new: str) -> None:
    warnings.warn(f"{old} is deprecated and will be removed in the next release; use {new}",
                  DeprecationWarning, stacklevel=3)
