"""
Identification from step responses
==================================

The paper's Sec. 3 (Fig. 2): the plant (T_mp, T_ms) -> (r_g, nu, nu_r) identified by an
approximate realisation of the nonlinear machine's step responses, the way one would identify
the real machine. empact also has the exact linearisation at the same point, so the
identified model can be checked against it: solid the identified, dashed the exact plant.
"""
import matplotlib.pyplot as plt
import numpy as np

import empact
from empact.lti import system_response
from empact.plotting import plot_identified_plant

params = empact.load_params()

# %%
# Step experiments on the nonlinear model at r_g = 1 (the parameter set's operating slip,
# clamping force and speed); the order is the smallest whose worst step fit reaches 98 %.
res = empact.identify_plant(params, params.operating.replace(r_g=1.0))
print("identified order:", res.realization.sys.nstates)

# %%
# Identified against exact, 0.2-100 Hz: the median relative error of each channel.
w = 2 * np.pi * np.logspace(np.log10(0.2), 2, 200)
H_id = system_response(res.realization.sys, w).H
H_ex = system_response(res.exact, w).H
err = np.median(np.abs(H_id - H_ex) / np.abs(H_ex), axis=-1)   # shape (n_out, n_in)
for i, out in enumerate(res.exact.output_labels):
    print(f"{out}: " + ", ".join(f"{inp} {err[i, j]:.1e}"
                                 for j, inp in enumerate(res.exact.input_labels)))
compared = plot_identified_plant(
    [res], np.logspace(-1, np.log10(200), 300),
    title="Identified (solid) and exact (dashed) plant, r_g = 1 (Fig. 2)")
plt.show()
