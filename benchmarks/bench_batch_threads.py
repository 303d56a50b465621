"""How to run a batch of landings on a few (shared) cores: thread pool vs numba prange.

Run:  python -m benchmarks.bench_batch_threads [--every 5] [--repeats 3] [--variants pool-2,pool-1]

The same compiled landing (``softlanding.simulation.kernel.landing.simulate_one``) on a
sample of the paper's grid (every ``--every``-th landing, k_d = 0 hops
included), scheduled five ways, each in its own process (numba's threading
layer is fixed per process), alternating, ``--repeats`` times:

* ``pool-2``: ``run_batch`` as shipped: 2 Python threads, each taking the next
  chunk of landings (GIL released) when done;
* ``pool-1``: the same on one thread;
* ``omp``, ``workqueue``: ``parallel=True`` with ``prange`` on numba's OpenMP or
  workqueue threading layer (static partition of the landings);
* ``omp-chunk``: OpenMP with ``numba.set_parallel_chunksize(64)`` (dynamic chunks).

Prints the median CPU time (all threads) and wall time of each, and the load.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

CHILD = str(Path(__file__).resolve().parent / "_batch_threads_child.py")

VARIANTS = {"pool-2": {}, "pool-1": {}, "omp": {"NUMBA_THREADING_LAYER": "omp"},
            "workqueue": {"NUMBA_THREADING_LAYER": "workqueue"},
            "omp-chunk": {"NUMBA_THREADING_LAYER": "omp"}}


def main() -> None:
    import json

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--every", type=int, default=5)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--variants", default=",".join(VARIANTS),
                    help="comma-separated, of: " + ", ".join(VARIANTS))
    a = ap.parse_args()
    names = [k.strip() for k in a.variants.split(",") if k.strip()]
    unknown = [k for k in names if k not in VARIANTS]
    if unknown or not names:
        ap.error(f"--variants: unknown {unknown}, choose from {', '.join(VARIANTS)}")
    print("before: load average {:.2f} {:.2f} {:.2f}".format(*os.getloadavg()))
    res: dict[str, list] = {k: [] for k in names}
    n = 0
    for r in range(a.repeats):
        for k in names if r % 2 == 0 else names[::-1]:
            env = dict(os.environ, **VARIANTS[k])
            p = subprocess.run([sys.executable, CHILD, k, str(a.every)], env=env,
                               capture_output=True, text=True, check=True)
            c, w, n = json.loads(p.stdout.strip().splitlines()[-1])
            res[k].append((c, w))
    print(f"{n} landings (every {a.every}th of the paper grid), {a.repeats} runs each, "
          f"medians:")
    for k, v in res.items():
        c, w = np.median(np.array(v), axis=0)
        print(f"  {k:10s} cpu {c:7.2f} s  wall {w:7.2f} s")
    print("after: load average {:.2f} {:.2f} {:.2f}".format(*os.getloadavg()))


if __name__ == "__main__":
    main()
