"""
Actuation modes and frequency responses
=======================================

The paper's Sec. 2.1: the actuation of the Empact CVT (servos, worm, epicyclic sets, screws,
sheaves and belt; Fig. 3) as a lumped linear model. Its modes at r_g = 1 (Figs. 4-5), and the
damped frequency responses of the two actuation modes of the machine: the primary servo
shifts (T_mp -> theta_mp), the secondary servo clamps (T_ms -> theta_ms) (Fig. 6).
"""
import matplotlib.pyplot as plt
import numpy as np

import empact
from empact.plotting import plot_bode, plot_mode_shapes

params = empact.load_params()

# %%
# Modes at r_g = 1: one rigid-body mode (a ratio change at constant belt length) and the
# calibrated 10.7 / 17.3 / 47.9 Hz.
act = empact.actuation_model(params, r_g=1.0)
modes = act.modes()
print("eigenfrequencies [Hz]:", np.round(modes.frequencies_hz, 1))
shapes = plot_mode_shapes(modes, split=4, title="Actuation mode shapes, r_g = 1")

# %%
# The two actuation modes, damped: frequency responses at three ratios. Frequencies are in
# rad/s in the API (``omega``); the plot labels them in Hz.
omega = 2 * np.pi * np.logspace(-1, 2.5, 400)
responses = [empact.actuation_model(params, r_g=r, damping="moderate")
             .frequency_response(omega, ["T_mp", "T_ms"], ["theta_mp", "theta_ms"],
                                 label=f"r_g = {r}")
             for r in (0.5, 1.0, 2.0)]
fig, axes = plt.subplots(2, 2, sharex=True, figsize=(9, 5))
plot_bode(responses, [("theta_mp", "T_mp"), ("theta_ms", "T_ms")], ax=axes)
plt.show()
