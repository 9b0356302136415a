"""The kernel lab's machine facts: bench/_host.py's (CPU model, SIMD width, load, host tag),
a one-line summary, and the one g++ command line of the scripts that compile C++ against the
library's headers (library_cxx)."""
from __future__ import annotations

import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "bench"))
from _host import (QUIET, _cpu_jiffies, busy_cores, cpu_model, host_tag, load, machine_info,  # noqa: E402,F401
                   simd_flags, simd_isa, wait_quiet)  # bench/_host.py

sys.path.remove(str(ROOT / "bench"))


def summary() -> str:
    """One line for a benchmark's header: CPU, ISA, cores, load."""
    return f"{cpu_model()} ({simd_isa()}), {os.cpu_count()} CPUs, load {load()[0]:.2f}"


def library_cxx(src, out, march="native", extra=()) -> list[str]:
    """g++ with the library's flags (-O3, no fast math, -ffp-contract=off) and include paths
    (cpp/include, Dr.Jit's headers) compiling src to out; extra flags (e.g. -S, -pthread) last."""
    import drjit  # lazily: only the scripts that compile need it

    return ["g++", "-std=c++17", "-O3", f"-march={march}", "-fno-math-errno", "-fno-trapping-math",
            "-ffp-contract=off", f"-I{ROOT / 'cpp' / 'include'}", "-isystem",
            str(Path(drjit.__file__).parent / "include"), str(src), "-o", str(out), *extra]
