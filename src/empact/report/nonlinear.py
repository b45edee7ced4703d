"""Report sections for the nonlinear model: NMP zeros (Sec. 2.3), a shift-and-load-step
simulation, and the exact (T_mp, T_ms) -> (r_g, nu) plant (the exact counterpart of Fig. 2)."""
from __future__ import annotations

import numpy as np

from ..nonlinear.simulation import write_csv
from ..plotting import plot_nmp, plot_plant_magnitude, plot_simulation
from ..reproduction import nonlinear as rep
from .context import Context

__all__ = ["nmp", "simulation", "exact_plant"]


def nmp(ctx: Context, res: rep.NmpSection) -> str:
    """Sec. 2.3.

    Parameters
    ----------
    ctx : Context
        The report build: figures and CSV tables are written to ``ctx.out`` in its formats;
        its ``params.operating`` is the point named.
    res : NmpSection
        The result of `empact.reproduction.nonlinear.nmp`.

    Returns
    -------
    str
        HTML: the geometry-and-zeros figure, the table of the geometry (Delta_x [mm], belt-length
        change over delta [-]) and right-half-plane zeros [Hz], the claims, a note and the table of
        the zeros by row set and slip signal.
    """
    r, g = res.result, res.result.geometry
    rows = [[rg, 1e3 * g.delta_x[k], g.dL_exact[k] / g.delta, rep.hz_text(r.rhp_zeros[k])]
            for k, rg in enumerate(r.r_g)]
    combo_rows = [["machine" if kin == rep.MACHINE else "Sec. 2.1 rows", sl]
                  + [rep.hz_text(rep.real_rhp(a.rhp_zeros[k])) for k in ks]
                  + [rep.hz_text(a.rhp_zeros[k][~np.isin(a.rhp_zeros[k],
                                                         rep.real_rhp(a.rhp_zeros[k]))
                                                & (a.rhp_zeros[k].imag > 0)]) for k in ks]
                  for kin, sl, a, ks in res.combos]
    op = ctx.params.operating
    title = r"Sec. 2.3 (machine): belt length and zeros of $T_\mathrm{mp} \rightarrow \nu$"
    return (ctx.figure(plot_nmp(r, title=title),
                       "nmp_zeros", "Sec. 2.3 on the machine: Delta_x and belt-length change "
                       "over the ratio (left); zeros of T_mp -> nu, eq. 2's slip (right, "
                       "filled: right half-plane)")
            + ctx.table("nmp_zeros", ["r_g", "Delta_x [mm]", "dL/delta exact [-]",
                                      "RHP zeros of T_mp -> nu [Hz]"], rows,
                        "Sec. 2.3 on the machine: geometry and right-half-plane zeros")
            + ctx.claims(res.claims)
            + f"<p>Zeros of the exactly linearised T_mp -> slip channel at {op.label()} "
              "(moderate damping, "
              "torque-controlled drive and load, creep law). The paper names neither the slip "
              "signal nor, consistently, the kinematics; the table separates both: the machine "
              "(equal translation) and the paper's Sec. 2.1 rows, and the slip nu of eq. 2 on "
              "the current radii or nu_r = 1 - omega_s / (r_g0 omega_p) at the operating ratio "
              "(eq. 3, Fig. 12). A real right-half-plane zero gives the inverse initial "
              "response Sec. 2.3 describes; complex right-half-plane pairs are listed "
              "apart.</p>"
            + ctx.table("nmp_conventions", ["rows", "slip"]
                        + [f"real RHP zeros, r_g = {x:g} [Hz]" for x in rep.RATIOS]
                        + [f"complex RHP pairs, r_g = {x:g} [Hz]" for x in rep.RATIOS],
                        combo_rows,
                        "Right-half-plane zeros of T_mp -> slip by row set and slip signal"))


def simulation(ctx: Context, res: rep.SimulationSection) -> str:
    """The simulation, its figure and CSV.

    Parameters
    ----------
    ctx : Context
        The report build: figures and CSV tables are written to ``ctx.out`` in its formats.
    res : SimulationSection
        The result of `empact.reproduction.nonlinear.simulation`.

    Returns
    -------
    str
        HTML: the time-history figure with a link to its CSV (``sim_shift_and_load_step.csv``,
        written too) and the claims.
    """
    write_csv(res.result, ctx.out / "sim_shift_and_load_step.csv")
    sc = res.scenario
    return (ctx.figure(plot_simulation(res.result), "sim_shift_and_load_step",
                       f"Scenario {sc.name}: {sc.description} "
                       f"(<a href='sim_shift_and_load_step.csv'>CSV</a>)")
            + ctx.claims(res.claims))


def exact_plant(ctx: Context, res: rep.PlantSection) -> str:
    """The exact plant's magnitudes, operating points and the load -> ratio gains.

    Parameters
    ----------
    ctx : Context
        The report build: figures and CSV tables are written to ``ctx.out`` in its formats;
        its ``params.operating`` is the point named.
    res : PlantSection
        The result of `empact.reproduction.nonlinear.exact_plant`.

    Returns
    -------
    str
        HTML: the plant-magnitude figure, the tables of the operating points and of the load ->
        ratio gains [1/(N m)], and the claims.
    """
    op = ctx.params.operating
    return (ctx.figure(plot_plant_magnitude(res.responses, title="Exact linearised plant, "
                                            + op.label()),
                       "fig2_exact_plant", "Fig. 2 (exact): magnitudes of T_mp, T_ms, T_l -> "
                       "r_g, nu, nu_r at r_g = 0.5, 1, 2, from the exact linearisation of "
                       "the nonlinear model (the machine, creep law)")
            + ctx.table("fig2_operating_points", ["r_g", "T_l [N m]", "T_mp [N m]",
                                                  "T_ms [N m]", "max Re(pole) [1/s]"], res.rows,
                        "Operating points of the exact plant")
            + ctx.table("load_to_ratio", ["r_g", "T_l [N m]", "DC gain T_l -> r_g [1/(N m)]",
                                          "from two trims [1/(N m)]", "max Re(pole) [1/s]"],
                        res.dc_rows,
                        "Static load -> ratio sensitivity with the servo torques held (test "
                        "bench: drive speed-controlled, load torque-controlled; torque ratio "
                        "0.5)")
            + ctx.claims(res.claims))
