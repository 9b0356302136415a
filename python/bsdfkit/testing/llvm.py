"""The libLLVM that Dr.Jit should load: one finder for the tests, the benchmarks and ``scripts/test``.

Dr.Jit 1.5 emits ``llvm.maximum``/``llvm.minimum``, which the x86 code generator of LLVM 15 and 16
cannot select (a process abort). :func:`configure_llvm_env` sets ``DRJIT_LIBLLVM_PATH`` to the newest
libLLVM >= :data:`MIN_WORKING_LLVM` before Dr.Jit is imported (``scripts/test`` prints its result;
``tools/perf/throughput.py`` loads this file by path so that its workers never import bsdfkit).
"""
import os
import re

__all__ = ["MIN_WORKING_LLVM", "find_libllvm", "configure_llvm_env"]

#: Oldest LLVM major version whose x86 backend can lower ``llvm.maximum`` (15 and 16 verified
#: broken, 19 verified working; 17 is where upstream added the x86 lowering).
MIN_WORKING_LLVM = 17

_LLVM15 = "/usr/lib/x86_64-linux-gnu/libLLVM-15.so.1"
_LIB_DIRS = ("/usr/lib/x86_64-linux-gnu", "/usr/lib/aarch64-linux-gnu", "/usr/lib64", "/usr/lib")
# libLLVM-15.so.1, libLLVM-14.0.6.so.1, libLLVM.so.19.1, libLLVM-19.so
_LLVM_NAME = re.compile(r"^libLLVM(?:-(\d+)(?:\.\d+)*\.so(?:\.\d+)*|\.so\.(\d+)(?:\.\d+)*)$")


def find_libllvm():
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


def configure_llvm_env():
    """Choose the libLLVM that Dr.Jit will load (must run before ``import drjit``).

    Respects an existing ``DRJIT_LIBLLVM_PATH``. Otherwise prefers the newest libLLVM with major
    version >= :data:`MIN_WORKING_LLVM`; failing that, uses ``libLLVM-15.so.1`` if present (it
    loads, but see the module docstring). Returns the path in effect, or ``None``."""
    current = os.environ.get("DRJIT_LIBLLVM_PATH")
    if current:
        return current
    libs = find_libllvm()
    good = [p for v, p in libs if v >= MIN_WORKING_LLVM]
    if good:
        os.environ["DRJIT_LIBLLVM_PATH"] = good[0]
    elif os.path.exists(_LLVM15):
        os.environ["DRJIT_LIBLLVM_PATH"] = _LLVM15
    return os.environ.get("DRJIT_LIBLLVM_PATH")

