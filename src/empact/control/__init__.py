"""Beyond the paper: plant families over the operating range, slip and ratio controllers,
their robustness across the family, and the closed loop on the nonlinear machine.

Modules
-------
family
    Plant families: the exact plant on a grid of operating points, interpolated (LPV).
design
    Controllers: decentralised PI for the family, H-infinity mixed sensitivity; the
    `Controller` record and its files.
robustness
    Closed-loop poles, disk margins and the structured singular value across a family.
closed_loop
    A controller inside the simulation of the nonlinear machine; scenarios and metrics.
"""
