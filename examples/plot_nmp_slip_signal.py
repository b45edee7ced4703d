"""
Non-minimum phase, by slip signal
=================================

The paper's Secs. 2.3 and 3: is the transfer from the primary servo torque T_mp to the slip
non-minimum phase? The paper never names its slip signal; empact offers both: ``nu`` of eq. 2
on the current radii and ``nu_r`` at the operating ratio (eq. 3, Fig. 12). On the exactly
linearised machine the two answer differently: ``nu_r`` has a real right-half-plane zero at
every ratio, ``nu`` at most a very slow one.
"""
import matplotlib.pyplot as plt

import empact
from empact.plotting import plot_nmp

params = empact.load_params()
ratios = (0.5, 1.0, 2.0)

fig, axes = plt.subplots(2, 2, figsize=(10, 7), layout="constrained")
for ax, slip in zip(axes, ("nu", "nu_r")):   # one row of two panels per slip signal
    res = empact.nmp_analysis(params, ratios, slip=slip)
    for r, n_real in zip(res.r_g, res.n_rhp_real):
        print(f"T_mp -> {slip} at r_g = {r:g}: {n_real} real RHP zero(s)")
    plot_nmp(res, title=f"Zeros of T_mp -> {slip}", ax=ax)
plt.show()
