"""The paper reproduced: every table and figure computed, and each of the paper's claims
about them checked (`Claim` records).

Modules
-------
claims
    The `Claim` record.
linear
    Tables 1-2, Figs. 4-6 and 8 (Sec. 2.1 and 2.2).
slip
    Figs. 9-13 and a stability map (Sec. 2.2, slip dynamics).
nonlinear
    Sec. 2.3 (non-minimum phase), a simulation, the exact Fig. 2 plant.
identification
    Fig. 2 by realisation with the Sec. 3 remarks; Fig. 14 on the virtual rig (Sec. 4).

Each function takes a parameter set and returns a result whose ``claims`` attribute is a tuple
of `Claim`; `empact.report` renders them.
"""
from .claims import Claim

__all__ = ["Claim"]
