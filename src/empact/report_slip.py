"""Report sections for the slip dynamics (paper Sec. 2.2 "Slip dynamics", Figs. 9-13).

Each section computes its result objects through `empact.slip` / `empact.traction`, draws them
with `empact.plotting_slip`, and states in one line what the paper says and whether the
computed result shows it.
"""
from __future__ import annotations

import html

import numpy as np

from . import paper
from .plotting_slip import (plot_belt_root_locus, plot_pole_sweep, plot_slip_bode,
                            plot_stability_map, plot_traction, plot_zero_locus)
from .report import Context, register, verdict
from .slip import (SlipOperatingPoint, belt_root_locus, coupled_limit, oscillatory, pole_sweep,
                   slip_frequency_responses, slip_model, stability_map, zero_locus)
from .traction import traction_curves, traction_from_params

#: Frequencies of the Fig. 12 responses [rad/s].
OMEGA = 2 * np.pi * np.logspace(np.log10(0.5), np.log10(200.0), 1500)


def _fig11_point(ctx: Context, nu: float = 0.01) -> SlipOperatingPoint:
    f = paper.FIG11_POINT
    return SlipOperatingPoint(r_g=f["r_g"], nu=nu, F_s=f["F_s"], omega_p=f["omega_p"])


def _rel(a: float, b: float) -> float:
    return abs(a / b - 1)


def _items(checks: dict[str, bool]) -> str:
    """HTML list of checks, each with its verdict."""
    return "".join(f"<li>{html.escape(k)}: {verdict(bool(v))}</li>" for k, v in checks.items())


@register("Figure 9: root locus over the belt damping c_b")
def fig9(ctx: Context) -> str:
    rl = belt_root_locus(ctx.params, 1.0)
    P = rl.locus.poles
    unc = np.sort([paper.UNCOUPLED_HZ["secondary"], paper.UNCOUPLED_HZ["primary"]])
    cou = np.array(paper.COUPLED_R1_HZ)
    err_u = max(_rel(a, b) for a, b in zip(rl.uncoupled_hz, unc))
    err_c = max(_rel(a, b) for a, b in zip(rl.coupled_hz, cou))
    hz = lambda p: np.abs(p) / (2 * np.pi)  # noqa: E731
    upper = [j for j in range(P.shape[1]) if P[0, j].imag > 1]
    hi = max(upper, key=lambda j: abs(P[0, j]))
    lo = min(upper, key=lambda j: abs(P[0, j]))
    lo_pair = [j for j in range(P.shape[1]) if np.isclose(abs(P[0, j]), abs(P[0, lo]))]
    real_axis = bool(np.any(np.all(np.abs(P[:, lo_pair].imag) < 1e-6 * abs(P[0, lo]), axis=1)))
    checks = {
        f"c_b = 0: uncoupled sides at {rl.uncoupled_hz[0]:.2f} and {rl.uncoupled_hz[1]:.2f} Hz "
        f"(paper 15.5 and 24.6 Hz; largest error {100 * err_u:.2f} %)": err_u < 0.01,
        f"c_b -> inf: coupled at {rl.coupled_hz[0]:.3f} and {rl.coupled_hz[1]:.3f} Hz (paper "
        f"4.14 and 22.5 Hz; largest error {100 * err_c:.2f} %)": err_c < 0.01,
        "the 15.5 Hz pair turns to the real axis": real_axis,
        "one real pole goes to -inf (at the largest c_b computed: "
        f"{P[-1].real.min():.3g} rad/s)": P[-1].real.min() < -100 * abs(rl.stop).max(),
        f"the 24.6 Hz pair ends at the 22.5 Hz coupled mode ({hz(P[-1, hi]):.3f} Hz)":
            _rel(hz(P[-1, hi]), cou[1]) < 0.01,
        "a rigid-body pole leaves 0 and (with a pole from the 15.5 Hz pair) ends in the 4.14 Hz "
        "pair": any(abs(P[0, j]) < 0.01 * abs(P[0, lo]) and _rel(hz(P[-1, j]), cou[0]) < 0.01
                    for j in range(P.shape[1])),
    }
    ok = all(checks.values())
    items = _items(checks)
    note = ("<p>Labels: the paper's text calls 15.5 Hz the primary side and 24.6 Hz the "
            "secondary side; with the Fig. 7 model only the swapped reading fits Table 2 (see "
            "Table 2 above), so here 24.6 Hz is the torque-converter (primary) side. The locus "
            f"runs over c_b = {rl.locus.parameter[0]:g} .. {rl.locus.parameter[-1]:g} N m s/rad "
            f"({len(rl.locus.parameter)} adaptive steps); the end points c_b = 0 and "
            "c_b -> inf are computed exactly.</p>")
    return (ctx.figure(plot_belt_root_locus(rl), "fig9_root_locus_cb",
                       "Fig. 9: the paper shows the poles moving from the uncoupled sides "
                       "(15.5, 24.6 Hz) to the coupled driveline (4.14, 22.5 Hz) as c_b grows "
                       f"- {verdict(ok)}")
            + f"<ul>{items}</ul>" + note)


@register("Figure 10: traction coefficient at LOW, MED and OD")
def fig10(ctx: Context) -> str:
    tr = traction_from_params(ctx.params)
    nu = np.linspace(0.0, 0.1, 2001)
    curves = traction_curves(tr, paper.FIG10_RATIOS, nu, label="(magic formula)")
    nu_pk, mu_pk = curves.peak()
    declining = [bool(curves.mu[k, -1] < mu_pk[k] - 1e-6) for k in range(3)]
    dmu_4 = float(tr.dmu(0.04, 1.0))
    checks = {
        "mu rises with nu to a maximum (slope positive below the peak)":
            all(np.all(curves.dmu[k, nu < nu_pk[k]] > 0) for k in range(3)),
        "beyond the maximum mu declines at some ratios (within 0-10 % slip: "
        + ", ".join(n for n, d in zip(("LOW", "MED", "OD"), declining) if d) + ")":
            any(declining),
        "peak values " + ", ".join(f"{m:.3f}" for m in mu_pk) + " in the published range "
        "0.09-0.12": bool(np.all((mu_pk >= 0.09 - 1e-9) & (mu_pk <= 0.12))),
        f"slope at r_g = 1, nu = 4 % is negative (mu' = {dmu_4:.4f})": dmu_4 < 0,
    }
    ok = all(checks.values())
    items = _items(checks)
    t = ctx.params.traction
    rows = [[name, r, B, C, D, E, 100 * nu_pk[k], mu_pk[k]] for k, (name, r, B, C, D, E) in
            enumerate([("LOW", t.r_low, t.B_low, t.C_low, t.D_low, t.E_low),
                       ("MED", t.r_med, t.B_med, t.C_med, t.D_med, t.E_med),
                       ("OD", t.r_od, t.B_od, t.C_od, t.D_od, t.E_od)])]
    table = ctx.table("fig10_traction_coefficients",
                      ["ratio", "r_g", "B", "C", "D", "E", "peak slip [%]", "peak mu"], rows,
                      "Magic-formula coefficients of the shipped parameter set")
    return (ctx.figure(plot_traction(curves, ["LOW", "MED", "OD"]), "fig10_traction",
                       "Fig. 10: the paper shows mu rising with slip to a maximum and "
                       f"declining beyond it at some ratios - {verdict(ok)}")
            + f"<ul>{items}</ul>" + table
            + "<p>The paper gives no numbers; the curves are chosen so that the statements of "
              "Figs. 11 and 12 hold with this driveline: a steep micro-slip rise (full "
              "coupling at 0.1 %), a flat top (weak coupling at 1-3 %) and, at r_g = 1, a "
              "negative slope by 4 %.</p>")


@register("Figure 11: poles over slip at r_g = 1, F_s0 = 10 kN, omega_p0 = 300 rad/s")
def fig11(ctx: Context) -> str:
    base = _fig11_point(ctx)
    nus = np.round(np.linspace(0.01, 0.045, 36), 6)  # weak coupling, as the paper's Fig. 11
    sw = pole_sweep(ctx.params, "nu", nus, base)
    rl = belt_root_locus(ctx.params, 1.0)
    osc = [sw.oscillatory(k) for k in range(len(nus))]
    two = all(len(f) == 2 for f, _ in osc)
    zeta = np.array([z for _, z in osc]) if two else np.zeros((len(nus), 2))
    decreasing = two and bool(np.all(np.diff(zeta, axis=0) < 0))
    k4 = int(np.argmin(np.abs(nus - 0.04)))
    weak = [k for k, n in enumerate(nus) if 0.01 - 1e-9 <= n <= 0.03 + 1e-9]
    freq = np.array([f for f, _ in osc]) if two else np.zeros((len(nus), 2))
    err_weak = float(np.max(np.abs(freq[weak] / rl.uncoupled_hz - 1))) if two else 1.0
    unstable_4 = bool(np.any(sw.poles[k4].real > 1e-6) and
                      np.any((sw.poles[k4].real > 1e-6) & (np.abs(sw.poles[k4].imag) > 1)))
    sign_ok = bool(np.all((sw.max_real > 1e-6) == (sw.dmu < 0)))
    checks = {
        "damping of both oscillatory pole pairs falls as nu grows (1-4.5 %)": decreasing,
        f"at nu = 4 % a pole pair lies in the right half-plane (Re = "
        f"{sw.poles[k4].real.max():+.3f} 1/s)": unstable_4,
        "poles in the right half-plane exactly where mu' < 0": sign_ok,
        f"weak coupling at 1-3 %: oscillatory poles within {100 * err_weak:.1f} % of the "
        "uncoupled frequencies (< 3 %)": err_weak < 0.03,
    }
    ok = all(checks.values())
    items = _items(checks)
    rows = []
    for nu in paper.FIG12_SLIPS:
        m = slip_model(ctx.params, base.replace(nu=nu))
        p = m.poles()
        p = p[p.imag > 1e-3]
        p = p[np.argsort(np.abs(p))]
        for q in p:
            rows.append([100 * nu, m.belt.dmu, m.belt.c_b, q.real, q.imag, abs(q) / (2 * np.pi),
                         -q.real / abs(q)])
    table = ctx.table("fig11_poles", ["nu [%]", "mu' [-]", "c_b [N m s/rad]", "Re [1/s]",
                                      "Im [rad/s]", "|p| [Hz]", "damping [-]"], rows,
                      "Oscillatory poles (upper half plane) at the Fig. 12a slips")
    note = ("<p>The sweep covers the weakly coupled slips (1-4.5 %), as the paper's Fig. 11. "
            "Between 0.1 % and about 0.6 % the model passes from full to weak coupling (back "
            "along the Fig. 9 locus): there the damping of the upper pair first rises to its "
            "largest value (about 0.05 at 0.6 %) before falling (see the table).</p>")
    return (ctx.figure(plot_pole_sweep(sw, uncoupled_hz=rl.uncoupled_hz,
                                       coupled_hz=rl.coupled_hz),
                       "fig11_poles_over_slip",
                       "Fig. 11: the paper shows the poles turning toward the imaginary axis as "
                       "nu grows and into the right half-plane where mu' &lt; 0, close to the "
                       f"uncoupled frequencies - {verdict(ok)}")
            + f"<ul>{items}</ul>" + table + note)


def _phase_step(model, f_hz: float, width: float = 0.06) -> float:
    """Phase change [deg] of ``F_s -> nu`` of `model` from ``f_hz (1 - width)`` to
    ``f_hz (1 + width)``, unwrapped on a fine local grid."""
    w = 2 * np.pi * f_hz * np.linspace(1 - width, 1 + width, 2001)
    ph = model.frequency_response(w, ["F_s"], ["nu"]).phase_deg()[0, 0]
    return float(ph[-1] - ph[0])


@register("Figure 12(a): F_s -> slip transfer functions over slip")
def fig12a(ctx: Context) -> str:
    base = _fig11_point(ctx)
    ops = [base.replace(nu=nu) for nu in paper.FIG12_SLIPS]
    labels = [f"nu = {100 * nu:g} %" for nu in paper.FIG12_SLIPS]
    resp = slip_frequency_responses(ctx.params, ops, OMEGA, labels)
    f01 = oscillatory(slip_model(ctx.params, ops[0]).poles())[0]
    err01 = max(_rel(a, b) for a, b in zip(f01, paper.COUPLED_R1_HZ)) if len(f01) == 2 else 1.0
    mag01 = resp[0].magnitude_db()[0, 0]
    flat01 = float(np.percentile(np.abs(mag01 - np.median(mag01)), 90))
    zetas = []
    for op in ops[1:]:
        zetas.append(oscillatory(slip_model(ctx.params, op).poles())[1])
    falling = bool(np.all(np.diff(np.array(zetas), axis=0) < 0))
    m4 = slip_model(ctx.params, ops[-1])
    p4 = m4.poles()
    steps = [_phase_step(m4, f) for f in oscillatory(p4)[0]]
    checks = {
        f"nu = 0.1 %: fully coupled, oscillatory poles at {', '.join(f'{x:.3f}' for x in f01)} "
        f"Hz (within {100 * err01:.2f} % of 4.14 and 22.5 Hz, target 2 %)": err01 < 0.02,
        f"nu = 0.1 %: completely different response, flat (90 % of the frequencies within "
        f"{flat01:.1f} dB of the median: the coupled poles nearly cancel the zeros)": flat01 < 3,
        "damping of both resonances decreases from nu = 0.5 % to 4 % ("
        + "; ".join(", ".join(f"{x:.3f}" for x in z) for z in zetas) + ")": falling,
        "nu = 4 %: phase increases at both resonances (unstable pairs): "
        + ", ".join(f"{s:+.0f} deg" for s in steps): len(steps) == 2 and min(steps) > 90,
    }
    ok = all(checks.values())
    items = _items(checks)
    return (ctx.figure(plot_slip_bode(resp, title="F_s -> nu at r_g = 1, F_s0 = 10 kN, "
                                                  "omega_p0 = 300 rad/s"),
                       "fig12a_frf_over_slip",
                       "Fig. 12(a): the paper shows full coupling at 0.1 %, damping of both "
                       "resonances falling with nu and a phase increase (instability) at 4 % - "
                       f"{verdict(ok)}")
            + f"<ul>{items}</ul>")


@register("Figure 12(b): F_s -> slip transfer functions over the ratio")
def fig12b(ctx: Context) -> str:
    base = _fig11_point(ctx, nu=ctx.params.operating.nu)
    ratios = (0.5, 1.0, 2.0)
    ops = [base.replace(r_g=r) for r in ratios]
    labels = [f"r_g = {r:g}" for r in ratios]
    resp = slip_frequency_responses(ctx.params, ops, OMEGA, labels)
    worst, dips = 0.0, []
    for r, op in zip(ratios, ops):
        zh = oscillatory(slip_model(ctx.params, op).zeros())[0]
        dips.append(zh)
        ref = np.array(paper.TABLE2_HZ[r][1:3])
        worst = max(worst, float(np.max(np.abs(zh / ref - 1))) if len(zh) == 2 else 1.0)
    moves = bool(np.all(np.abs(np.diff(np.array(dips), axis=0)) > 0.1))
    checks = {
        "two zeros (anti-resonances) whose frequencies depend on r_g: "
        + "; ".join(f"r_g = {r:g}: {', '.join(f'{x:.2f}' for x in d)} Hz"
                    for r, d in zip(ratios, dips)): moves,
        f"the zeros sit at the coupled eigenfrequencies of Table 2 (modes 2, 3; largest "
        f"difference {100 * worst:.2f} %)": worst < 0.01,
    }
    ok = all(checks.values())
    items = _items(checks)
    return (ctx.figure(plot_slip_bode(resp, title=f"F_s -> nu at nu = {100 * base.nu:g} %, "
                                                  "F_s0 = 10 kN, omega_p0 = 300 rad/s"),
                       "fig12b_frf_over_ratio",
                       "Fig. 12(b): the paper shows that the two zeros of F_s -> nu move with "
                       f"the ratio - {verdict(ok)}")
            + f"<ul>{items}</ul>")


@register("Figure 13: zeros of F_s -> slip over the ratio")
def fig13(ctx: Context) -> str:
    base = _fig11_point(ctx, nu=ctx.params.operating.nu)
    ratios = np.linspace(0.43, 2.25, 60)
    zl = zero_locus(ctx.params, ratios, base)
    coupled = np.sort(np.abs(zl.coupled), axis=1)[:, ::2] / (2 * np.pi)
    diff = float(np.nanmax(np.abs(zl.zero_hz / coupled - 1)))
    # independence of the traction slope: the same zeros at 0.1 % and 4 % slip up to rho
    f_lo = oscillatory(slip_model(ctx.params, base.replace(nu=0.001)).zeros())[0]
    f_hi = oscillatory(slip_model(ctx.params, base.replace(nu=0.04)).zeros())[0]
    shift = float(np.max(np.abs(f_hi / f_lo - 1)))
    f_rho = oscillatory(coupled_limit(ctx.params, 1.0, 0.04))[0]
    rho_ok = bool(np.allclose(f_rho, f_hi, rtol=1e-6))
    mono = bool(np.all(np.diff(zl.zero_hz[:, 0]) > 0) and np.all(np.diff(zl.zero_hz[:, 1]) < 0))
    checks = {
        "two zero pairs on the imaginary axis whose location depends on r_g (lower one rises, "
        "upper one falls with r_g)": bool(zl.zeros.shape[1] == 4 and mono
                                          and np.nanmax(np.abs(zl.zeros.real)) < 1e-6 *
                                          np.nanmax(np.abs(zl.zeros))),
        f"the zeros equal the poles of the coupled driveline c_b -> inf (largest difference "
        f"{diff:.1e})": diff < 1e-6,
        f"the zeros do not depend on mu' (nu = 0.1 % vs 4 %: {100 * shift:.2f} % shift, all of "
        "it from the kinematic ratio r_g (1 - nu))": rho_ok,
    }
    ok = all(checks.values())
    items = _items(checks)
    ref = {r: paper.TABLE2_HZ[r][1:3] for r in paper.TABLE2_HZ}
    rows = []
    for r in paper.TABLE2_HZ:
        zh = oscillatory(slip_model(ctx.params, base.replace(r_g=r)).zeros())[0]
        rows.append([r, zh[0], zh[1], ref[r][0], ref[r][1]])
    table = ctx.table("fig13_zeros", ["r_g", "zero 1 [Hz]", "zero 2 [Hz]", "Table 2 mode 2 [Hz]",
                                      "Table 2 mode 3 [Hz]"], rows,
                      "Zeros of F_s -> nu and the coupled eigenfrequencies of Table 2")
    return (ctx.figure(plot_zero_locus(zl, reference_hz=ref), "fig13_zero_locus",
                       "Fig. 13: the paper shows the two zeros of the slip model moving with "
                       f"r_g - {verdict(ok)}")
            + f"<ul>{items}</ul>" + table
            + "<p>Why: F_s enters along the belt-damper direction and the linearised slip is "
              "the damper's own velocity, so F_s -> nu is g H / (1 + c_s H) with the belt-free "
              "H: its zeros are those of H for every c_b, i.e. the end points of the Fig. 9 "
              "root locus.</p>")


@register("Stability map over slip and ratio")
def stability(ctx: Context) -> str:
    base = _fig11_point(ctx)
    nu = np.linspace(0.0005, 0.06, 240)
    r = np.linspace(0.43, 2.25, 200)
    sm = stability_map(ctx.params, "nu", nu, "r_g", r, base=base)
    tr = traction_from_params(ctx.params)
    negative = tr.dmu(nu[None, :], r[:, None]) < 0
    agree = float(np.mean(sm.unstable == negative))
    k1 = int(np.argmin(np.abs(r - 1.0)))
    edge = nu[np.argmax(sm.unstable[k1])] if sm.unstable[k1].any() else np.nan
    checks = {
        f"unstable exactly where mu' < 0 ({100 * agree:.2f} % of {sm.max_real.size} points "
        "agree)": agree == 1.0,
        f"at r_g = 1 the boundary lies between 3 % and 4 % slip ({100 * edge:.2f} %)":
            bool(0.03 < edge <= 0.04),
    }
    ok = all(checks.values())
    items = _items(checks)
    return (ctx.figure(plot_stability_map(sm), "slip_stability_map",
                       "Stability map (not in the paper): the paper says negative traction "
                       "slope makes the coupling unstable; the map shows where, over slip and "
                       f"ratio at F_s0 = 10 kN, omega_p0 = 300 rad/s - {verdict(ok)}")
            + f"<ul>{items}</ul>"
            + f"<p>{sm.max_real.size} operating points, batched in chunks (stacked 5x5 reduced "
              f"matrices, one eigenvalue call per chunk); {100 * sm.unstable_fraction:.1f} % "
              "unstable.</p>")
