"""Child process of bench_simulator.py: the paper grid alone (current kernel), peak RSS."""

import resource
import time

import numpy as np

from softlanding import Robot, simulate_batch


def rss() -> float:
    """Peak RSS in MiB: VmHWM (Linux) belongs to this program alone, whereas ru_maxrss
    survives execve and so includes the parent's peak at the fork."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


simulate_batch(Robot(5, 20), [-1.0], [0.2], [0.2])  # JIT load
rss0 = rss()
g = np.round(np.linspace(0, 1, 101), 12)
v = np.round(np.linspace(-10, 0, 21), 12)
KP, KD, V = np.meshgrid(g, g, v, indexing="ij")
c, w = time.process_time(), time.perf_counter()
simulate_batch(Robot(5, 20), V, KP, KD, progress=False)
c, w = time.process_time() - c, time.perf_counter() - w
print(f"  fresh process, current kernel only: grid cpu {c:.2f} s, wall {w:.2f} s; peak RSS "
      f"{rss():.0f} MiB (after imports and JIT load {rss0:.0f} MiB)")
