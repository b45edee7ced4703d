"""
A plant family exported to MATLAB
=================================

A plant family (the machine trimmed and exactly linearised over 4 ratios x 2 torque ratios)
written as a ``.mat`` file, and read back with scipy the way MATLAB sees it: ``A`` is an array
of shape ``(n, n, n_r_g, n_tau)``, the grid dimensions last, as an ``ss`` array wants them. In
MATLAB::

    s = load('family.mat');
    sys = ss(s.A, s.B, s.C, s.D, 'InputName', cellstr(s.inputs), ...
             'OutputName', cellstr(s.outputs), 'StateName', cellstr(s.states));
    sys.SamplingGrid = struct('r_g', s.grid_r_g, 'tau', s.grid_tau);

The plot compares the exported point's frequency response with the family's own plant.
"""
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from scipy.io import loadmat

import empact
from empact.control.family import save_family
from empact.lti import frequency_response

params = empact.load_params()
family = empact.plant_family(params, r_g=[0.5, 1.0, 1.5, 2.0], tau=[0.8, 0.9])
path = save_family(family, Path(tempfile.mkdtemp()) / "family.mat")

# %%
# What MATLAB's ``load`` gets: names as cell arrays of char (``cellstr`` takes them), the
# grid dimensions last.
s = loadmat(path)
inputs = [str(n[0]) for n in s["inputs"].ravel()]
outputs = [str(n[0]) for n in s["outputs"].ravel()]
print("A:", s["A"].shape, " inputs:", inputs, " outputs:", outputs)
print("grid r_g:\n", s["grid_r_g"])

# %%
# The exported point (r_g = 1, tau = 0.9) against the family's plant: T_mp -> r_g.
i, j = 1, 1
A, B, C, D = (s[k][..., i, j] for k in "ABCD")
omega = 2 * np.pi * np.logspace(-2, 2, 300)
H_mat = frequency_response(A, B, C, D, omega, inputs, outputs).H[outputs.index("r_g"),
                                                                  inputs.index("T_mp")]
plant = family.plant((i, j))
H_fam = frequency_response(plant.A, plant.B, plant.C, plant.D, omega, plant.inputs,
                           plant.outputs).H[plant.outputs.index("r_g"),
                                            plant.inputs.index("T_mp")]
print("largest relative difference:", np.max(np.abs(H_mat - H_fam) / np.abs(H_fam)))
fig, ax = plt.subplots(figsize=(7, 4), layout="constrained")
ax.loglog(omega / (2 * np.pi), np.abs(H_fam), label="family plant")
ax.loglog(omega / (2 * np.pi), np.abs(H_mat), "--", label="read back from family.mat")
ax.set(xlabel="frequency [Hz]", ylabel="|r_g / T_mp| [1/(N m)]",
       title="T_mp -> r_g at r_g = 1, tau = 0.9")
ax.legend()
plt.show()
