"""The report's sections, in order: title, anchor, computation, rendering."""
from __future__ import annotations

from ..reproduction import control as rctl
from ..reproduction import drive_cycle as rcyc
from ..reproduction import identification as rid
from ..reproduction import linear as rlin
from ..reproduction import machine as rmach
from ..reproduction import nonlinear as rnl
from ..reproduction import slip as rslip
from . import control, drive_cycle, identification, linear, machine, nonlinear, slip
from .context import Section

__all__ = ["SECTIONS"]

SECTIONS: tuple[Section, ...] = (
    Section("Table 1: undamped actuation eigenfrequencies", "table1", rlin.table1,
            linear.table1),
    Section("Table 2: undamped driveline eigenfrequencies", "table2", rlin.table2,
            linear.table2),
    Section("Figures 4 and 5: actuation mode shapes and modal energy at r_g = 1", "fig4-5",
            rlin.fig4_5, linear.fig4_5, cost=1.9),
    Section("Figure 6: damped actuation transfer functions", "fig6", rlin.fig6, linear.fig6,
            cost=2.3),
    Section("Figure 8: driveline mode shapes and modal energy at r_g = 1", "fig8", rlin.fig8,
            linear.fig8),
    Section("Figure 9: root locus over the belt damping c_b", "fig9", rslip.fig9, slip.fig9),
    Section("Figure 10: traction coefficient at LOW, MED and OD", "fig10", rslip.fig10,
            slip.fig10),
    Section("Figure 11: poles over slip at r_g = 1, F_s0 = 10 kN, omega_p0 = 300 rad/s",
            "fig11", rslip.fig11, slip.fig11),
    Section("Figure 12(a): F_s -> slip transfer functions over slip", "fig12a", rslip.fig12a,
            slip.fig12a),
    Section("Figure 12(b): F_s -> slip transfer functions over the ratio", "fig12b",
            rslip.fig12b, slip.fig12b),
    Section("Figure 13: zeros of F_s -> slip over the ratio", "fig13", rslip.fig13, slip.fig13),
    Section("Stability map over slip and ratio", "stability", rslip.stability, slip.stability),
    Section("Sec. 2.3: non-minimum-phase behaviour of T_mp -> nu (nonlinear model, exact)",
            "nmp", rnl.nmp, nonlinear.nmp, cost=1.6),
    Section("Nonlinear simulation: LOW -> OD shift and a load step", "simulation",
            rnl.simulation, nonlinear.simulation, cost=1.7),
    Section("Exact linear plant (T_mp, T_ms; T_l) -> (r_g, nu, nu_r): the counterpart of "
            "Fig. 2",
            "exact-plant", rnl.exact_plant, nonlinear.exact_plant, cost=2.5),
    Section("Figure 2: (T_mp, T_ms) -> (r_g, nu, nu_r) by approximate realisation from step "
            "responses", "fig2", rid.fig2, identification.fig2, cost=3.3),
    Section("Figure 14: FRFs on the virtual test rig (r_g = 0.5, nu0 = 0)", "fig14", rid.fig14,
            identification.fig14, cost=2.7),
    Section("Beyond the paper: the machine sheet (traction, creep, thrust ratio, torque "
            "reserve, efficiency)", "machine", rmach.machine, machine.machine, cost=2.0),
    Section("Beyond the paper: slip and ratio control on the machine (family, loop, closed "
            "loop)", "control", rctl.control, control.control, cost=15.0),
    Section("Beyond the paper: control studies (traction estimate, Monte Carlo, the "
            "clamping saving)", "control-studies", rctl.control_studies, control.studies,
            cost=75.0),
    Section("Beyond the paper: drive cycle (WLTC 3b in a car, quasi-static and dynamic)",
            "drive-cycle", rcyc.drive_cycle, drive_cycle.drive_cycle, cost=120.0),
)
