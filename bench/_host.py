"""The machine a benchmark ran on (CPU model, SIMD width, load, the reports' host tag) and the
timing rules the benchmarks share (wait for a quiet machine, record what it was).

One reader for every script in bench/ (and tools/perf/, whose _machine.py re-exports it).
Machines of this kind differ (Intel with AVX-512, AMD Zen 3 with AVX2 only, AMD Zen 4 with
AVX-512) and are shared, so a figure is quoted as a ratio measured in the same run, with these
facts written next to it.
"""
from __future__ import annotations

import datetime as _dt
import os
import platform
import subprocess
import time

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


def host_tag(tag: str) -> str:
    """A --tag naming a kind of host in report file names (RESULTS_<tag>.md): letters, digits,
    '-' and '_'. An argparse type, so a bad tag stops the script before it measures anything."""
    if not tag or not all(c.isalnum() or c in "-_" for c in tag):
        import argparse  # lazily: only the scripts with a --tag need it
        raise argparse.ArgumentTypeError(f"letters, digits, '-' and '_' only, got {tag!r}")
    return tag


def machine_info():
    """The facts a report states about the run: date, CPU, SIMD flags, memory, versions, load."""
    import numpy as np

    cpu, simd = cpu_model(), simd_flags()
    mem = None
    try:
        mem = next(l.split()[1] for l in open("/proc/meminfo") if l.startswith("MemTotal"))
        mem = f"{int(mem) / 2**20:.1f} GiB"
    except (OSError, StopIteration):
        pass
    import bsdfkit as bk
    info = {"date": _dt.datetime.now().astimezone().isoformat(timespec="seconds"), "nproc": os.cpu_count(),
            "cpu": cpu, "simd": simd, "mem": mem, "platform": platform.platform(),
            "python": platform.python_version(), "numpy": np.__version__, "bsdfkit": bk.__version__,
            "load_avg_start": os.getloadavg()}
    try:
        info["gcc"] = subprocess.run(["gcc", "-dumpfullversion"], capture_output=True, text=True).stdout.strip()
    except OSError:
        pass
    try:
        import importlib.metadata as md
        info["mitsuba"] = md.version("mitsuba")
        info["drjit"] = md.version("drjit")
    except Exception:
        pass
    return info


def _cpu_jiffies():
    """The all-CPU row of /proc/stat: user nice system idle iowait irq softirq steal ..."""
    with open("/proc/stat") as f:
        return [int(x) for x in f.readline().split()[1:]]


def _cpu_times():
    v = _cpu_jiffies()
    return sum(v[:8]), v[3] + v[4]  # total, idle + iowait


QUIET = {"budget_s": 60.0, "waited_s": 0.0, "busy_samples": []}


def busy_cores(dt=0.1):
    """CPU cores kept busy by other processes over dt seconds (this process sleeps meanwhile)."""
    try:
        t0, i0 = _cpu_times()
        time.sleep(dt)
        t1, i1 = _cpu_times()
    except OSError:
        return 0.0
    return (os.cpu_count() or 1) * (1 - (i1 - i0) / max(1, t1 - t0))


def wait_quiet(threshold=0.3, max_wait=15.0):
    """On a shared machine, wait (bounded, from a global budget) until other processes use less
    than `threshold` cores; returns the busy cores seen when measuring starts."""
    t0 = time.perf_counter()
    b = busy_cores()
    while b > threshold and time.perf_counter() - t0 < max_wait and QUIET["waited_s"] < QUIET["budget_s"]:
        time.sleep(0.4)
        b = busy_cores()
        QUIET["waited_s"] += 0.5
    QUIET["busy_samples"].append(round(b, 2))
    return b
