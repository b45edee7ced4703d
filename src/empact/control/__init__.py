"""Beyond the paper: plant families over the operating range, slip and ratio controllers,
their robustness across the family, and the closed loop on the nonlinear machine.

Modules
-------
family
    Plant families: the exact plant on a grid of operating points, interpolated (LPV).
controller
    The `Controller` record (state space, gain schedule) and its files.
pi, hinf
    Controller design: decentralised PI for the family (`design_pi`), H-infinity mixed
    sensitivity (`design_hinf`).
designs
    The registry of controller types by name (what ``empact control design --method``
    offers; how to add one).
robustness
    Closed-loop poles, disk margins and the structured singular value across a family.
loop, law
    The sampled loop law (sensors, feedforwards, servo limits) and its linear model across a
    family.
shifting
    Ratio shifts: the envelope of rates the machine can follow.
closed_loop
    A controller inside the simulation of the nonlinear machine; scenarios and metrics.
"""
