"""Large read-only tables held by reference: a file path plus its content digest.

A model parameter that is a large table (a measured BRDF, a lookup table shipped as a file) is a
:class:`TableRef`, so ``==``, ``hash``, ``repr`` and pickle of the model cost as much as a short
string: two references are equal when their contents (digests) are equal, and the array is read
once per process and shared (``load``). The Filament DFG table is the in-memory case of the same
idea: models hold its size, and the table itself lives in a per-process cache.
"""
from __future__ import annotations

import hashlib
import os
import threading

__all__ = ["TableRef"]

_CACHE: dict = {}
_LOCK = threading.Lock()


def _digest(path: str) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return "sha256:" + h.hexdigest()


class TableRef:
    """A table file by reference: ``TableRef(path)`` reads the file once to compute its digest;
    ``TableRef(path, digest=...)`` (what ``repr`` and pickle produce) checks it lazily, on
    :meth:`load`. Equality and hash are by digest (the content), not by path."""

    __slots__ = ("path", "digest")

    def __init__(self, path, digest: str | None = None):
        p = os.fspath(path)
        if not isinstance(p, str):
            raise TypeError(f"path: expected a str or os.PathLike, got {type(path).__name__}")
        if digest is None:
            if not os.path.isfile(p):
                raise OSError(f"path: no such table file: {p!r}")
            digest = _digest(p)
        elif not (isinstance(digest, str) and digest.startswith("sha256:")):
            raise ValueError(f"digest: expected 'sha256:<hex>', got {digest!r}")
        object.__setattr__(self, "path", p)
        object.__setattr__(self, "digest", digest)

    def __setattr__(self, k, v):
        raise AttributeError("TableRef is immutable")

    def __eq__(self, other):
        return isinstance(other, TableRef) and self.digest == other.digest

    def __hash__(self):
        return hash(self.digest)

    def __repr__(self):
        return f"TableRef({self.path!r}, digest={self.digest!r})"

    def __reduce__(self):
        return (TableRef, (self.path, self.digest))

    def load(self, reader):
        """``reader(path)`` once per (digest, reader) and process; later calls share the result.
        Raises OSError when the file's content no longer matches the digest."""
        key = (self.digest, reader)
        with _LOCK:
            if key not in _CACHE:
                actual = _digest(self.path)
                if actual != self.digest:
                    raise OSError(f"path: {self.path!r} changed since it was referenced "
                                  f"(digest {actual} != {self.digest})")
                _CACHE[key] = reader(self.path)
            return _CACHE[key]
