"""
A Monte Carlo study
===================

How robust are the plant's dynamics to the parameters the paper does not publish? A Monte
Carlo study draws parameter sets from a spread (a TOML file: a few percent on the actuation
stiffnesses, the traction peak, the driveshaft and the operating torque ratio; here the
shipped example), trims and linearises the machine for each and collects the slow plant mode
and the right-half-plane zero. Each run draws from its own random stream, so the table does
not depend on where or in which order the runs are computed; a failed run is kept with its
reason.
"""
from importlib.resources import files

import matplotlib.pyplot as plt
import numpy as np

import empact

params = empact.load_params()
spread = empact.load_spread(files("empact.data") / "montecarlo" / "example-spread.toml", params)
print("spread over:")
for name in spread.names:
    print("   ", name)
study = empact.monte_carlo(params, spread, 200, "plant", seed=1)
summary = study.summary()
print(f"{summary['succeeded']} of {summary['runs']} runs succeeded; failures: "
      f"{summary['failure_reasons'] or 'none'}")

# %%
# The distributions of the slowest resonant pair [Hz] and of the RHP zero [Hz].
fig, axes = plt.subplots(1, 2, figsize=(10, 3.5), layout="constrained")
for ax, name in zip(axes, ("f_slow_hz", "rhp_zero_hz")):
    v = study.values[:, study.outputs.index(name)]
    v = v[np.isfinite(v)]
    ax.hist(v, bins=25)
    ax.set(xlabel=f"{name} [{study.units[name]}]", ylabel="runs",
           title=f"{name}: median {np.median(v):.3g}, 5-95 % {np.percentile(v, 5):.3g}-"
                 f"{np.percentile(v, 95):.3g}")
plt.show()
