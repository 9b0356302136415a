"""Independent reference implementations used to test bsdfkit.

Submodules (imported lazily, so ``import bsdfkit`` never pulls in Mitsuba/Dr.Jit):

``bsdfkit.references.mitsuba``
    Mitsuba 3 (``llvm_ad_rgb`` variant, float32) evaluated and sampled in bsdfkit/pbrt-v4
    conventions, microfacet component references and a wrapper around Mitsuba's chi^2 test.
``bsdfkit.references.drjit_models``
    Float64 re-derivations of the pbrt-v4 formulas (Trowbridge-Reitz, Fresnel, rough
    conductor/dielectric, diffuse transmission) written with Dr.Jit.

Both need a working Dr.Jit LLVM backend for vectorized evaluation. Dr.Jit 1.5 emits the
``llvm.maximum``/``llvm.minimum`` intrinsics, which the x86 code generator of LLVM 15 and 16 cannot
select ("LLVM ERROR: Cannot select: fmaximum", a process abort, not an exception). LLVM 19
(Debian 12: ``apt-get install libllvm19``) works. :func:`_configure_llvm_env` therefore points
``DRJIT_LIBLLVM_PATH`` at the newest libLLVM it can find, before Dr.Jit is imported.
"""

import os
import re

__all__ = []

#: Oldest LLVM major version whose x86 backend can lower ``llvm.maximum`` (15 and 16 verified
#: broken, 19 verified working; 17 is where upstream added the x86 lowering).
MIN_WORKING_LLVM = 17

_LLVM15 = "/usr/lib/x86_64-linux-gnu/libLLVM-15.so.1"
_LIB_DIRS = ("/usr/lib/x86_64-linux-gnu", "/usr/lib/aarch64-linux-gnu", "/usr/lib64", "/usr/lib")
# libLLVM-15.so.1, libLLVM-14.0.6.so.1, libLLVM.so.19.1, libLLVM-19.so
_LLVM_NAME = re.compile(r"^libLLVM(?:-(\d+)(?:\.\d+)*\.so(?:\.\d+)*|\.so\.(\d+)(?:\.\d+)*)$")


def _find_libllvm():
    """Return ``[(major, path), ...]`` of the libLLVM shared objects found in the usual
    system folders, newest first (symlinks resolved, duplicates removed)."""
    found = {}
    for d in _LIB_DIRS:
        try:
            names = os.listdir(d)
        except OSError:
            continue
        for name in names:
            m = _LLVM_NAME.match(name)
            if not m:
                continue
            real = os.path.realpath(os.path.join(d, name))
            if os.path.isfile(real):
                found.setdefault(real, int(m.group(1) or m.group(2)))
    return sorted(((v, p) for p, v in found.items()), reverse=True)


def _configure_llvm_env():
    """Choose the libLLVM that Dr.Jit will load (must run before ``import drjit``).

    Respects an existing ``DRJIT_LIBLLVM_PATH``. Otherwise prefers the newest libLLVM with major
    version >= :data:`MIN_WORKING_LLVM`; failing that, uses ``libLLVM-15.so.1`` if present (it
    loads, but see the module docstring). Returns the path in effect, or ``None``."""
    current = os.environ.get("DRJIT_LIBLLVM_PATH")
    if current:
        return current
    libs = _find_libllvm()
    good = [p for v, p in libs if v >= MIN_WORKING_LLVM]
    if good:
        os.environ["DRJIT_LIBLLVM_PATH"] = good[0]
    elif os.path.exists(_LLVM15):
        os.environ["DRJIT_LIBLLVM_PATH"] = _LLVM15
    return os.environ.get("DRJIT_LIBLLVM_PATH")


_DRJIT = None


def _drjit_backend():
    """``(dr, B)``: Dr.Jit and its LLVM array module (``drjit.scalar`` where the LLVM backend is
    missing), with FastMath off so the references keep full float64 accuracy. Imported and
    configured once per process, after :func:`_configure_llvm_env`."""
    global _DRJIT
    if _DRJIT is None:
        _configure_llvm_env()
        import drjit as dr
        if dr.has_backend(dr.JitBackend.LLVM):
            import drjit.llvm as B
        else:  # pragma: no cover - machine dependent
            import drjit.scalar as B
        dr.set_flag(dr.JitFlag.FastMath, False)
        _DRJIT = (dr, B)
    return _DRJIT
