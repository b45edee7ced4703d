"""
A closed-loop load step on the machine
======================================

Slip control on the nonlinear machine (beyond the paper): the shipped gain-scheduled PI holds
the slip set-point (torque ratio 0.9, an 11 % torque reserve) through the clamping while the
load torque steps by 50 % of the torque capacity at 0.5 s. The law that runs is the sampled one
(1 kHz, sensors with a sample of delay, the clamping feedforward, servo limits); the scenario
is a shipped TOML file.
"""
import matplotlib.pyplot as plt

import empact
from empact.control.closed_loop import check_targets, control_example_path
from empact.nonlinear.scenario import load_scenario
from empact.plotting import plot_closed_loop

params = empact.load_params()
scenario = load_scenario(control_example_path("slip-load-step-r1"))
run = empact.run_closed_loop(scenario, params)

# %%
# The metrics are judged on the machine's true signals (slips and slip errors as fractions,
# 0.01 is 1 %); the scenario's ``[targets]`` are checked against them.
m = run.metrics
print(f"peak slip error {100 * m['peak_slip_error']:.2f} pp, macro slip: {m['macro_slip']}")
for check in check_targets(m, scenario.targets):
    print(check.describe())
figure = plot_closed_loop([run], title="Load step of 50 % of the torque capacity at r_g = 1")
plt.show()
