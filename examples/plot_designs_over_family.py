"""
PI and H-infinity designs checked over a family
===============================================

A plant family is the machine trimmed and exactly linearised on a grid of operating points
(here 5 ratios x 3 torque ratios on the test bench). A decentralised PI (the largest integral
action that keeps every plant stable with a stated multiloop disk margin) and an S/KS
mixed-sensitivity H-infinity controller (designed on the nominal plant) are both checked
against every plant of the family: closed-loop stability and the multiloop disk margin.
"""
import matplotlib.pyplot as plt
import numpy as np

import empact

params = empact.load_params()
family = empact.plant_family(params, r_g=np.geomspace(0.5, 2.0, 5), tau=[0.8, 0.9, 0.95])
print("family:", family.shape, "plants; inputs", family.plant((0, 0)).inputs)

# %%
# One fixed (not scheduled) PI for the whole family: crossovers of 0.1 Hz (ratio) and 0.25 Hz
# (slip) on the nominal plant, disk margin at least 0.3 everywhere (a design that cannot meet
# it is refused with one line naming what to relax). The H-infinity design here is the
# full-order one of the continuous nominal plant (no ``loop=``) at 0.1 / 0.05 Hz; the shipped
# ``hinf.json`` is the multi-model design on the sampled loop (``design_hinf(..., loop=,
# params=)``, the control chapter).
designs = {"PI": empact.design_pi(family, bandwidth_hz=(0.1, 0.25), alpha_min=0.3),
           "H-infinity": empact.design_hinf(family, bandwidth_hz=(0.1, 0.05))}

# %%
# Each design against the whole family: the largest closed-loop real part [1/s] (< 0 is
# stable) and the multiloop disk margin alpha [-] at every grid point.
fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharey=True)
for ax, (name, controller) in zip(axes, designs.items()):
    rmap = empact.robustness_map(family, controller)
    stable = rmap.max_real_pole < 0
    print(f"{name}: {stable.sum()} of {stable.size} plants stable, "
          f"smallest disk margin {rmap.disk_margin.min():.2f}")
    r_g, tau = family.axes["r_g"], family.axes["tau"]
    mesh = ax.pcolormesh(tau, r_g, rmap.disk_margin, vmin=0, vmax=1, shading="nearest")
    ax.set(title=f"{name}: disk margin alpha [-]", xlabel="torque ratio tau [-]")
    ax.set_yscale("log")
axes[0].set_ylabel("ratio r_g [-]")
fig.colorbar(mesh, ax=axes)
plt.show()
