"""Report sections for the nonlinear model: NMP zeros (Sec. 2.3), a shift-and-load-step
simulation, and the exact (T_mp, T_ms) -> (r_g, nu) plant (the exact counterpart of Fig. 2)."""
from __future__ import annotations

from ..nonlinear.simulation import write_csv
from ..plotting import plot_nmp, plot_plant_magnitude, plot_simulation
from ..reproduction import nonlinear as rep
from .context import Context

__all__ = ["nmp", "simulation", "exact_plant"]


def nmp(ctx: Context, res: rep.NmpSection) -> str:
    """Sec. 2.3."""
    r, g = res.result, res.result.geometry
    rows = [[rg, 1e3 * g.delta_x[k], g.dL_exact[k] / g.delta, rep.hz_text(r.rhp_zeros[k])]
            for k, rg in enumerate(r.r_g)]
    combo_rows = [[kin, sl] + [rep.hz_text(a.rhp_zeros[k]) for k in ks]
                  for kin, sl, a, ks in res.combos]
    eq2_pattern = [kin for kin, sl, a, ks in res.combos
                   if sl == "eq2" and a.n_rhp[ks[0]] > 0 and a.n_rhp[ks[-1]] == 0]
    op = ctx.params.operating
    title = r"Sec. 2.3: belt length and zeros of $T_\mathrm{mp} \rightarrow \nu$"
    return (ctx.figure(plot_nmp(r, title=title),
                       "nmp_zeros", "Sec. 2.3: Delta_x and belt-length change over the ratio "
                       "(left); zeros of T_mp -> nu (right, filled: right half-plane)")
            + ctx.table("nmp_zeros", ["r_g", "Delta_x [mm]", "dL/delta exact [-]",
                                      "RHP zeros of T_mp -> nu [Hz]"], rows,
                        "Sec. 2.3: geometry and right-half-plane zeros")
            + ctx.claims(res.claims)
            + f"<p>Zeros of the exactly linearised T_mp -> nu channel at nu = {op.nu:g}, F_s = "
              f"{op.F_s:g} N, omega_p = {op.omega_p:g} rad/s (moderate damping, "
              "torque-controlled drive and load). The table below separates the two choices "
              "the paper leaves open: the sheave kinematics (Sec. 2.1 'actuation', or Sec. 1 / "
              "2.3 'equal-translation', where the primary servo alone translates both sheaves "
              "equally) and the slip signal (eq. 2 on the current radii, or the speed slip "
              "1 - omega_s / (r_g0 omega_p) at the operating ratio). The equal-translation "
              "kinematics cannot give Sec. 2.1's mode shapes (README, 'Paper "
              "inconsistencies'). With eq. 2's slip, the slip the model outputs, the pattern "
              f"appears under {' and '.join(eq2_pattern) or 'neither kinematics'}.</p>"
            + ctx.table("nmp_conventions", ["kinematics", "slip"]
                        + [f"RHP zeros at r_g = {x:g} [Hz]" for x in rep.RATIOS], combo_rows,
                        "Right-half-plane zeros of T_mp -> nu by kinematics and slip signal"))


def simulation(ctx: Context, res: rep.SimulationSection) -> str:
    """The simulation, its figure and CSV."""
    write_csv(res.result, ctx.out / "sim_shift_and_load_step.csv")
    sc = res.scenario
    return (ctx.figure(plot_simulation(res.result), "sim_shift_and_load_step",
                       f"Scenario {sc.name}: {sc.description} "
                       f"(<a href='sim_shift_and_load_step.csv'>CSV</a>)")
            + ctx.claims(res.claims))


def exact_plant(ctx: Context, res: rep.PlantSection) -> str:
    """The exact plant's magnitudes and operating points."""
    op = ctx.params.operating
    return (ctx.figure(plot_plant_magnitude(res.responses, title=r"Exact linearised plant, $\nu$ = "
                                            f"{op.nu:g}, $F_s$ = {op.F_s / 1e3:g} kN, "
                                            rf"$\omega_p$ = {op.omega_p:g} rad/s"),
                       "fig2_exact_plant", "Fig. 2 (exact): magnitudes of T_mp, T_ms -> r_g, nu "
                       "at r_g = 0.5, 1, 2, from the complex-step linearisation of the "
                       "nonlinear model")
            + ctx.table("fig2_operating_points", ["r_g", "T_l [N m]", "T_mp [N m]",
                                                  "T_ms [N m]", "max Re(pole) [1/s]"], res.rows,
                        "Operating points of the exact plant"))
