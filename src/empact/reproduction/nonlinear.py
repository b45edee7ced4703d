"""The nonlinear model's part of the paper reproduced: non-minimum-phase behaviour (Sec. 2.3),
a shift-and-load-step simulation, and the exact (T_mp, T_ms) -> (r_g, nu) plant (the exact
counterpart of Fig. 2).  Compute only: `empact.report` renders."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..lti import FrequencyResponse, system_response
from ..nonlinear.linearization import plant
from ..nonlinear.nmp import NmpResult, nmp_analysis
from ..nonlinear.scenario import Scenario, example_path, load_scenario
from ..nonlinear.simulation import SimulationResult, run_scenario
from ..params import Params
from .claims import Claim

__all__ = ["RATIOS", "hz_text", "NmpSection", "SimulationSection", "PlantSection", "nmp",
           "simulation", "exact_plant"]

RATIOS = (0.5, 1.0, 2.0)


def hz_text(zeros) -> str:
    """Zeros [rad/s] as '+re +imj' in Hz, or 'none'."""
    return "; ".join(f"{v.real / 2 / np.pi:+.3g} {v.imag / 2 / np.pi:+.3g}j" for v in zeros) \
        or "none"


@dataclass(frozen=True)
class NmpSection:
    """Sec. 2.3: zeros over the ratio (shipped model, `result`) and the table of the four
    kinematics / slip-signal combinations (``combos``: (kinematics, slip, NmpResult,
    indices of the ratios 0.5, 1, 2))."""

    result: NmpResult
    combos: list[tuple[str, str, NmpResult, list[int]]]
    claims: tuple[Claim, ...]


def nmp(params: Params) -> NmpSection:
    """Sec. 2.3: Delta_x, belt-length change and the zeros of T_mp -> nu over the ratio."""
    op = params.operating
    ratios = np.geomspace(0.45, 2.25, 13)
    res = nmp_analysis(params, np.unique(np.r_[ratios, RATIOS]))
    g = res.geometry
    at = {float(r): n for r, n in zip(res.r_g, res.n_rhp)}
    geo_ok = bool(g.dL_exact[res.r_g < 1].max() < 0 < g.dL_exact[res.r_g > 1].min())
    shipped = [int(np.flatnonzero(np.isclose(res.r_g, r))[0]) for r in RATIOS]
    combos = [("actuation", "eq2", res, shipped)] + [
        (kin, sl, nmp_analysis(params, RATIOS, kinematics=kin, slip=sl), [0, 1, 2])
        for kin, sl in (("actuation", "speed"), ("equal-translation", "eq2"),
                        ("equal-translation", "speed"))]
    et_speed = combos[3][2]
    et_ok = bool(et_speed.n_rhp_real[0] > 0 and et_speed.n_rhp[-1] == 0)
    point = f"nu = {op.nu:g}, F_s = {op.F_s:g} N, omega_p = {op.omega_p:g} rad/s"
    src = "Sec. 2.3"
    shipped_reading = "Sec. 2.1 kinematics ('actuation', shipped), eq. 2 slip"
    claims = (
        Claim(key="nmp.geometry", source=src,
              claim="for an equal translation of both sheaves the belt length falls below "
                    "r_g = 1 and rises above it (first order 4 phi delta / tan(beta))",
              computed=f"dL / delta from {g.dL_exact.min() / g.delta:.3f} to "
                       f"{g.dL_exact.max() / g.delta:.3f} over r_g = {res.r_g[0]:.3g}.."
                       f"{res.r_g[-1]:.3g}", shown=geo_ok,
              explanation="The sign of the exact belt-length change does not follow r_g - 1."),
        Claim(key="nmp.rhp_at_0.5", source="Secs. 2.3 and 3",
              claim="T_mp -> nu has a right-half-plane zero at r_g = 0.5",
              computed=f"{hz_text(res.rhp_zeros[shipped[0]])} Hz at {point}",
              shown=at[0.5] > 0, reading=shipped_reading,
              explanation="No right-half-plane zero at r_g = 0.5."),
        Claim(key="nmp.none_at_2", source="Secs. 2.3 and 3",
              claim="T_mp -> nu has no right-half-plane zero at r_g = 2",
              computed=f"{hz_text(res.rhp_zeros[shipped[2]])} Hz at {point}",
              shown=at[2.0] == 0, reading=shipped_reading,
              explanation="With the sheave kinematics that Sec. 2.1's mode shapes require "
                          "(calibrated to Table 1), a primary-servo rotation against the "
                          "inertia-held secondary sun squeezes both sheaves and changes the "
                          "clamping force directly, whatever the sign of phi: a real "
                          "right-half-plane zero near 1 Hz appears at every ratio."),
        Claim(key="nmp.equal_translation_speed_slip", source="Secs. 2.3 and 3",
              claim="RHP zero at r_g = 0.5 and none at r_g = 2",
              computed=f"r_g = 0.5: {hz_text(et_speed.rhp_zeros[0])} Hz; r_g = 2: "
                       f"{hz_text(et_speed.rhp_zeros[2])} Hz", shown=et_ok,
              reading="equal-translation kinematics (Secs. 1, 2.3), speed slip "
                      "1 - omega_s / (r_g0 omega_p)",
              explanation="The pattern does not appear under this reading either."),
    )
    return NmpSection(res, combos, claims)


@dataclass(frozen=True)
class SimulationSection:
    """The shipped shift-and-load-step scenario and its result."""

    scenario: Scenario
    result: SimulationResult
    claims: tuple[Claim, ...]


def simulation(params: Params) -> SimulationSection:
    """Simulate the shipped LOW -> OD shift with a load step."""
    sc = load_scenario(example_path("shift-and-load-step"))
    res = run_scenario(sc, params)
    r = res.output("r_g")
    claim = Claim(key="simulation.complete", source="(empact: nonlinear model, Sec. 3 setting)",
                  claim="the nonlinear model runs the LOW -> OD shift and the load step",
                  computed=f"{res.message}; ratio {r[0]:.3g} -> {r[-1]:.3g}; largest slip "
                           f"{100 * res.output('nu').max():.2f} %; clamping force "
                           f"{res.output('F_s').min() / 1e3:.1f}-"
                           f"{res.output('F_s').max() / 1e3:.1f} kN",
                  shown=res.complete, explanation=res.message)
    return SimulationSection(sc, res, (claim,))


@dataclass(frozen=True)
class PlantSection:
    """Exact plants at r_g = 0.5, 1, 2: responses and the operating-point table (``rows``)."""

    responses: list[FrequencyResponse]
    rows: list[list[float]]
    claims: tuple[Claim, ...]


def exact_plant(params: Params) -> PlantSection:
    """The exact (T_mp, T_ms) -> (r_g, nu) plant at r_g = 0.5, 1, 2 (``params.operating``)."""
    f = np.logspace(-1, 3, 600)
    resps, rows = [], []
    for r in RATIOS:
        sys, op = plant(params, params.operating.replace(r_g=r))
        resps.append(system_response(sys, 2 * np.pi * f, label=f"r_g = {r:g}"))
        ev = np.linalg.eigvals(sys.A)
        rows.append([r, op.T_l, op.T_mp, op.T_ms, float(ev.real.max())])
    return PlantSection(resps, rows, ())
