"""The machine a benchmark ran on: CPU model, SIMD width, cores, load.

One reader for every script in bench/ (each used to carry its own copy), the one g++ command
line the scripts that compile C++ against the library's headers share (library_cxx), and the
reports' host tag (host_tag). Machines of this kind differ (Intel with AVX-512, AMD Zen 3 with
AVX2 only, AMD Zen 4 with AVX-512) and are shared, so a figure is quoted as a ratio
measured in the same run, with these facts written next to it.
"""
from __future__ import annotations

import os
import platform
from pathlib import Path

_SIMD_FLAGS = ("avx2", "fma", "avx512f", "avx512vl")


def _cpuinfo_field(name: str) -> str | None:
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith(name):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return None


def cpu_model() -> str:
    """The CPU's model name ("AMD EPYC ...", "Intel(R) Xeon(R) ..."), or the best platform guess."""
    return _cpuinfo_field("model name") or platform.processor() or platform.machine() or "unknown"


def simd_flags() -> list[str]:
    """Which of avx2, fma, avx512f, avx512vl the CPU reports."""
    flags = set((_cpuinfo_field("flags") or "").split())
    return [f for f in _SIMD_FLAGS if f in flags]


def simd_isa() -> str:
    """The widest vector ISA: "AVX-512", "AVX2" or "SSE"."""
    flags = simd_flags()
    return "AVX-512" if "avx512f" in flags else "AVX2" if "avx2" in flags else "SSE"


def load() -> tuple[float, float, float]:
    """The 1/5/15-minute load averages, rounded to 2 digits."""
    return tuple(round(x, 2) for x in os.getloadavg())


def summary() -> str:
    """One line for a benchmark's header: CPU, ISA, cores, load."""
    return f"{cpu_model()} ({simd_isa()}), {os.cpu_count()} CPUs, load {load()[0]:.2f}"


def library_cxx(src, out, march="native", extra=()) -> list[str]:
    """g++ with the library's flags (-O3, no fast math, -ffp-contract=off) and include paths
    (cpp/include, Dr.Jit's headers) compiling src to out; extra flags (e.g. -S, -pthread) last."""
    import drjit  # lazily: only the scripts that compile need it

    return ["g++", "-std=c++17", "-O3", f"-march={march}", "-fno-math-errno", "-fno-trapping-math",
            "-ffp-contract=off", f"-I{Path(__file__).resolve().parent.parent / 'cpp' / 'include'}", "-isystem",
            str(Path(drjit.__file__).parent / "include"), str(src), "-o", str(out), *extra]


def host_tag(tag: str) -> str:
    """A --tag naming a kind of host in report file names (RESULTS_<tag>.md): letters, digits,
    '-' and '_'. An argparse type, so a bad tag stops the script before it measures anything."""
    if not tag or not all(c.isalnum() or c in "-_" for c in tag):
        import argparse  # lazily: only the scripts with a --tag need it
        raise argparse.ArgumentTypeError(f"letters, digits, '-' and '_' only, got {tag!r}")
    return tag
