"""Numbers published in the reference paper, for comparison in reports and tests.

Source: "Dynamic analysis of the Empact CVT: ratio and slip dependent, non-minimum phase
dynamics" (the project's reference paper).  Copied here so that the project does not need
the paper at run time.
"""
from __future__ import annotations

#: Table 2, undamped driveline eigenfrequencies [Hz] by ratio r_g; modes 1-4.
TABLE2_HZ: dict[float, tuple[float, float, float, float]] = {
    0.5: (0.0, 3.52, 24.0, 236.0),
    1.0: (0.0, 4.14, 22.5, 205.0),
    2.0: (0.0, 5.38, 19.7, 184.0),
}

#: Sec. 2.1 text: actuation eigenfrequencies at r_g = 1 [Hz], modes 2-4 (Table 1 itself is
#: missing from the text); modes 5 and 6 are "at very high frequency".
ACTUATION_R1_HZ: tuple[float, float, float] = (10.7, 17.3, 47.9)

#: Sec. 2.2 "Slip dynamics": uncoupled sides (belt removed) [Hz].  The text labels 15.5 Hz the
#: primary side and 24.6 Hz the secondary side; only the swapped reading fits Table 2 (see
#: README, "Paper inconsistencies"), which is what is listed here.
UNCOUPLED_HZ: dict[str, float] = {"primary": 24.6, "secondary": 15.5}

#: Sec. 2.2: fully coupled driveline at r_g = 1, end of the c_b root locus [Hz].
COUPLED_R1_HZ: tuple[float, float] = (4.14, 22.5)

#: Fig. 11 operating point: r_g, F_s0 [N], omega_p0 [rad/s].
FIG11_POINT = {"r_g": 1.0, "F_s": 10e3, "omega_p": 300.0}

#: Fig. 12(a) slip values [-].  The paper states only 0.1 % (fully coupled) and 4.0 %
#: (unstable); the intermediate curves are a reading ("the paper gives none; read near the
#: traction peak"): 2-3 %, below the MED peak (3.3 % on the shipped curve), so that only the
#: 4 % curve is unstable, as the paper's text says.
FIG12_SLIPS: tuple[float, ...] = (0.001, 0.02, 0.025, 0.03, 0.04)
#: Fig. 11 slip range [-] (a reading: the paper gives none; its poles end in the right
#: half-plane "when mu' becomes negative", so the range straddles the traction peak).
FIG11_SLIPS: tuple[float, float] = (0.025, 0.045)

#: Fig. 10 ratios LOW, MED, OD.
FIG10_RATIOS: tuple[float, float, float] = (0.43, 1.0, 2.25)
