"""
Driveline and slip root loci
============================

The paper's Sec. 2.2: the slipping belt couples the two sides of the driveline like a damper
``c_b`` (eq. 3). Over ``c_b`` the poles move from the uncoupled sides (``c_b = 0``) to the
kinematically coupled driveline (``c_b -> inf``) (Fig. 9). Over the slip ``nu`` at r_g = 1,
10 kN and 300 rad/s, a pole pair crosses into the right half-plane where the traction curve
falls (``mu' < 0``): macro slip is unstable (Fig. 11).
"""
import matplotlib.pyplot as plt
import numpy as np

import empact
from empact.plotting import plot_belt_root_locus, plot_pole_sweep

params = empact.load_params()

# %%
# Root locus over the belt damping c_b [N m s/rad] at r_g = 1.
rl = empact.belt_root_locus(params, r_g=1.0)
locus = plot_belt_root_locus(rl, title="Poles over the belt damping c_b, r_g = 1 (Fig. 9)")

# %%
# Poles over the slip (a fraction: 0.01 is 1 %) at the paper's Fig. 11 point.
base = empact.OperatingPoint(r_g=1.0, nu=0.01, F_s=10e3, omega_p=300.0)
sweep = empact.pole_sweep(params, "nu", np.linspace(0.002, 0.06, 60), base)
unstable = sweep.values[np.any(sweep.poles.real > 0, axis=1)]
print(f"unstable from a slip of {unstable.min():.3f} [-] on")
poles = plot_pole_sweep(sweep, title="Poles over slip, r_g = 1, 10 kN, 300 rad/s (Fig. 11)")
plt.show()
