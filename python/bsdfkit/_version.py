"""The package version, read from the installed distribution's metadata (pyproject.toml's
``[project] version`` is the single source)."""
from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("bsdfkit")
except PackageNotFoundError:  # pragma: no cover - running from a source tree that was never installed
    __version__ = "0+unknown"
