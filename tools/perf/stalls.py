"""Latency of small and medium multi-threaded calls: the distribution of single-call times of
``m.eval`` on N pairs with 1 and 2 threads (issue 11 item 5).

With an OpenMP team, a 2-thread call on a busy 2-core machine intermittently took 8 or 16 ms (a
scheduler slice): the caller waited at the team's join barrier for a helper the OS had not run
yet. The pool in cpp/include/bsdfkit/pool.h lets the caller finish the work itself instead. A
stall shows as a large p99 / max against the median; compare the 2-thread row with the 1-thread
row of the same run (both see the same load).

    python tools/perf/stalls.py [--n 65536] [--calls 300]
"""
from __future__ import annotations

import argparse
import time

import numpy as np

import bsdfkit as bk


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, nargs="+", default=[4096, 65536, 262144])
    ap.add_argument("--calls", type=int, default=300)
    a = ap.parse_args(argv)
    m = bk.Conductor.from_metal("Cu", alpha=0.3, fresnel="schlick")
    rng = np.random.default_rng(0)
    wo = bk.direction(theta=np.radians(40), phi=0.0)
    try:
        load = open("/proc/loadavg").read().split()[0]
    except OSError:
        load = "?"
    print(f"bsdfkit {bk.__file__}; load average {load} on {bk._core.hardware_concurrency()} cores")
    print(f"{'N':>8s} {'threads':>7s} {'median ms':>9s} {'p90 ms':>8s} {'p99 ms':>8s} {'max ms':>8s} {'> 4 ms':>7s}")
    nt0 = bk.get_num_threads()
    for n in a.n:
        wi = rng.normal(size=(n, 3))
        wi /= np.linalg.norm(wi, axis=1, keepdims=True)
        out = np.empty((n, 3))
        for nt in (1, 2):
            bk.set_num_threads(nt)
            m.eval(wo, wi, out=out)
            ts = np.empty(a.calls)
            for k in range(a.calls):
                t0 = time.perf_counter()
                m.eval(wo, wi, out=out)
                ts[k] = time.perf_counter() - t0
            ts *= 1e3
            print(f"{n:8d} {nt:7d} {np.median(ts):9.3f} {np.quantile(ts, .9):8.3f} {np.quantile(ts, .99):8.3f} "
                  f"{ts.max():8.2f} {int((ts > 4).sum()):7d}")
    bk.set_num_threads(nt0)


if __name__ == "__main__":
    main()
