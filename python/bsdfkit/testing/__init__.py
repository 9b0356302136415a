"""Independent reference implementations used to test bsdfkit.

Submodules (imported lazily, so ``import bsdfkit`` never pulls in Mitsuba/Dr.Jit):

``bsdfkit.testing.mitsuba``
    Mitsuba 3 (``llvm_ad_rgb`` variant, float32) evaluated and sampled in bsdfkit/pbrt-v4
    conventions, microfacet component references and a wrapper around Mitsuba's chi^2 test.
``bsdfkit.testing.llvm``
    The one libLLVM finder for Dr.Jit, shared by the tests, the benchmarks and ``scripts/test``
``bsdfkit.testing.drjit_models``
    Float64 re-derivations of the pbrt-v4 formulas (Trowbridge-Reitz, Fresnel, rough
    conductor/dielectric, diffuse transmission) written with Dr.Jit.

Both need a working Dr.Jit LLVM backend for vectorized evaluation. Dr.Jit 1.5 emits the
``llvm.maximum``/``llvm.minimum`` intrinsics, which the x86 code generator of LLVM 15 and 16 cannot
select ("LLVM ERROR: Cannot select: fmaximum", a process abort, not an exception). LLVM 19
(Debian 12: ``apt-get install libllvm19``) works. :func:`bsdfkit.testing.llvm.configure_llvm_env` therefore points
``DRJIT_LIBLLVM_PATH`` at the newest libLLVM it can find, before Dr.Jit is imported.
"""

from .llvm import MIN_WORKING_LLVM, configure_llvm_env as _configure_llvm_env, find_libllvm  # noqa: F401

__all__ = ["MIN_WORKING_LLVM", "find_libllvm"]

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
