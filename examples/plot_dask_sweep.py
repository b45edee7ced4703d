"""
A sweep on a local Dask cluster
===============================

The stability of the slip dynamics over slip and ratio (a stability map), computed on a local
Dask cluster of two worker processes and again in process. The work goes out in chunks; the
results come back in grid order and are bitwise those of the serial run. On a real cluster,
give a scheduler address instead of ``"local"`` (see :doc:`../dask`). Dask is the optional
``dask`` extra.

A local cluster starts its workers as new processes, which import the script again: the
work goes under ``if __name__ == "__main__":``, as in any script that starts processes.
"""
import time

import matplotlib.pyplot as plt
import numpy as np

import empact
from empact.plotting import plot_stability_map

params = empact.load_params()
nu = np.linspace(0.001, 0.06, 120)
r_g = np.geomspace(0.5, 2.2, 120)

if __name__ == "__main__":
    t0 = time.perf_counter()
    on_dask = empact.stability_map(params, "nu", nu, "r_g", r_g,
                                   sweep=empact.SweepOptions("local", workers=2))
    t1 = time.perf_counter()
    serial = empact.stability_map(params, "nu", nu, "r_g", r_g)
    t2 = time.perf_counter()
    print(f"{nu.size * r_g.size} points: local cluster {t1 - t0:.1f} s (with its start-up), "
          f"in process {t2 - t1:.2f} s")
    print("bitwise equal to the serial run:",
          np.array_equal(on_dask.max_real, serial.max_real, equal_nan=True))
    smap = plot_stability_map(on_dask, title="Stability over slip and ratio (computed on Dask)")
    plt.show()
