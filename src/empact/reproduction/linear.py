"""The paper's Sec. 2.1 and 2.2 reproduced: Tables 1-2 and Figs. 4-6 and 8, with their claims.

Each function computes the result objects a figure or table is drawn from and checks the
paper's statements about them (`Claim` records).  Compute only: `empact.report` renders.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .. import paper
from ..linear.actuation import actuation_model
from ..linear.driveline import driveline_model, uncoupled_frequencies
from ..linear.lumped import Modes
from ..lti import FrequencyResponse
from ..params import DAMPING_LEVELS, Params
from .claims import Claim

__all__ = ["RATIOS", "MACHINE", "SEC21", "READING", "Table1", "Table2", "ModeFigure", "Fig6",
           "table1", "table2", "fig4_5", "fig6", "fig8", "mode_characters"]

#: The ratios of the paper's tables.
RATIOS = (0.5, 1.0, 2.0)


#: The two actuation row sets: the machine and the paper's Sec. 2.1 rows as published.
MACHINE, SEC21 = "equal-translation", "paper-sec2.1"
READING = {MACHINE: "the machine: equal-translation rows, stiffnesses [actuation]",
           SEC21: "the paper's Sec. 2.1 rows as published, stiffnesses [paper_sec21]"}


@dataclass(frozen=True)
class Table1:
    """Actuation eigenfrequencies [Hz] by kinematics and ratio
    (``frequencies_hz[kinematics][r]``, shape (6,)).

    Attributes
    ----------
    frequencies_hz : dict of str to dict of float to array
        Undamped eigenfrequencies [Hz], shape (6,) each, ascending (the rigid-body mode at 0),
        by row set (`MACHINE`, `SEC21`) and ratio (`RATIOS`).
    claims : tuple of Claim
        The checks of the paper's statements (``table1.r1``, ``table1.machine``).
    """

    frequencies_hz: dict[str, dict[float, np.ndarray]]
    claims: tuple[Claim, ...]


def table1(params: Params) -> Table1:
    """Table 1: undamped actuation eigenfrequencies at r_g = 0.5, 1, 2, for the machine and
    for the Sec. 2.1 rows.

    Parameters
    ----------
    params : Params
        The parameter set (e.g. `empact.load_params`).

    Returns
    -------
    Table1
        The eigenfrequencies of both row sets and the claims.
    """
    freqs = {kin: {r: actuation_model(params, r, kinematics=kin).modes().frequencies_hz
                   for r in RATIOS} for kin in (MACHINE, SEC21)}
    ref = np.array(paper.ACTUATION_R1_HZ)
    claims = []
    for kin, key in ((SEC21, "table1.r1"), (MACHINE, "table1.machine")):
        f1 = freqs[kin][1.0]
        achieved = f1[1:4]
        err = np.abs(achieved / ref - 1)
        claims.append(Claim(
            key=key, source="Sec. 2.1 (Table 1)",
            claim="actuation eigenfrequencies 10.7, 17.3 and 47.9 Hz at r_g = 1; modes 5 and 6 "
                  "at very high frequency",
            computed=f"{', '.join(f'{x:.2f}' for x in achieved)} Hz (largest relative error "
                     f"{100 * err.max():.2f} %, target 1 %); modes 5 and 6 at {f1[4]:.0f} "
                     f"and {f1[5]:.0f} Hz",
            shown=bool(err.max() < 0.01 and f1[4] > 500),
            explanation="The paper's Table 1 is missing from its text; the targets are the "
                        "numbers in its prose. 'Very high frequency' is checked as above "
                        "500 Hz.", reading=READING[kin],
            values={"frequencies_hz": achieved.tolist(), "max_rel_error": float(err.max()),
                    "mode5_hz": float(f1[4]), "mode6_hz": float(f1[5])}))
    return Table1(freqs, tuple(claims))


@dataclass(frozen=True)
class Table2:
    """Driveline eigenfrequencies [Hz] by ratio and the uncoupled sides.

    Attributes
    ----------
    frequencies_hz : dict of float to array
        ``{r_g: array (4,)}``: the eigenfrequencies [Hz] at each ratio of `RATIOS`.
    uncoupled_hz : dict of str to float
        ``{"primary": f, "secondary": f}``: the uncoupled sides' natural frequencies [Hz].
    claims : tuple of Claim
        The checks.
    """

    frequencies_hz: dict[float, np.ndarray]
    uncoupled_hz: dict[str, float]
    claims: tuple[Claim, ...]


def table2(params: Params) -> Table2:
    """Table 2: undamped driveline eigenfrequencies, and the uncoupled sides of Sec. 2.2.

    Parameters
    ----------
    params : Params
        The parameter set (e.g. `empact.load_params`).

    Returns
    -------
    Table2
        The driveline eigenfrequencies, the uncoupled sides and the claims.
    """
    freqs = {r: driveline_model(params, r).modes().frequencies_hz for r in RATIOS}
    worst = max(abs(freqs[r][j] / ref - 1) for r in RATIOS
                for j, ref in enumerate(paper.TABLE2_HZ[r]) if ref)
    unc = uncoupled_frequencies(params)
    worst_u = max(abs(unc[s] / paper.UNCOUPLED_HZ[s] - 1) for s in ("primary", "secondary"))
    claims = (
        Claim(key="table2.modes", source="Sec. 2.2 (Table 2)",
              claim="driveline eigenfrequencies at r_g = 0.5, 1, 2 as in Table 2",
              computed=f"largest relative error {100 * worst:.2f} % (target 1 %)",
              shown=worst < 0.01, explanation="All nine non-zero values compared.",
              values={"max_rel_error": float(worst)}),
        Claim(key="table2.uncoupled", source="Sec. 2.2 (slip dynamics)",
              claim="with the belt removed, one side at 15.5 Hz and the other at 24.6 Hz",
              computed=f"primary side {unc['primary']:.3f} Hz, secondary side "
                       f"{unc['secondary']:.3f} Hz (largest error {100 * worst_u:.2f} %)",
              shown=worst_u < 0.01,
              explanation="The paper's text calls 15.5 Hz the primary side and 24.6 Hz the "
                          "secondary side, but no parameter set of the Fig. 7 model reproduces "
                          "Table 2 with those labels, while the swapped reading fits all of "
                          "Table 2 and agrees with the paper's own root-locus story (the "
                          "24.6 Hz pair ends at the 22.5 Hz torque-converter mode).",
              reading="labels swapped (primary 24.6 Hz, secondary 15.5 Hz); the paper's own "
                      "labels are judged under Fig. 9",
              values={"primary_hz": unc["primary"], "secondary_hz": unc["secondary"]}),
    )
    return Table2(freqs, unc, claims)


@dataclass(frozen=True)
class ModeFigure:
    """Undamped modes at one ratio (Figs. 4-5 for the actuation, Fig. 8 for the driveline);
    for the actuation also the machine's (`machine`) and the mode characters of both
    (`characters`: rows of mode, frequency and description per kinematics).

    Attributes
    ----------
    modes : Modes
        The undamped modes at r_g = 1: the actuation with the Sec. 2.1 rows (Figs. 4-5) or the
        driveline (Fig. 8).
    claims : tuple of Claim
        The checks of the paper's statements (one per mode character checked).
    machine : Modes or None
        The machine's actuation modes at r_g = 1 (None for Fig. 8).
    characters : list of list
        Rows ``[row set, mode number, frequency [Hz], character]`` (`mode_characters`) of both
        row sets; empty for Fig. 8.
    """

    modes: Modes
    claims: tuple[Claim, ...]
    machine: Modes | None = None
    characters: list[list[object]] = field(default_factory=list)


def _checks(key: str, source: str, checks: dict[str, tuple[bool, str]],
            reading: str = "", why: str = "") -> tuple[Claim, ...]:
    """One claim per check: ``{claim text: (shown, computed)}``."""
    return tuple(Claim(key=f"{key}.{i + 1}", source=source, claim=text, computed=computed,
                       shown=ok, reading=reading, explanation="" if ok else (
                           why or "The computed mode shape or energy does not have this "
                           "character."))
                 for i, (text, (ok, computed)) in enumerate(checks.items()))


def mode_characters(modes: Modes) -> list[str]:
    """A one-line character of each actuation mode: the springs holding most of its
    potential energy and, for the rigid-body mode, which coordinates move.

    Parameters
    ----------
    modes : Modes
        Actuation modes (`empact.linear.lumped.Modes` of `empact.actuation_model`: five springs,
        worm, chain, belt and the two bearings).

    Returns
    -------
    list of str
        One line per mode, in the order of ``modes.omega``: the springs with at least 10 % of the
        mode's potential energy, largest first, or the rigid-body mode's coordinates that stay.
    """
    e = modes.energy_fraction
    names = ("worm", "chain", "belt", "primary bearing", "secondary bearing")
    out = []
    for j in range(len(modes.omega)):
        if modes.omega[j] == 0:
            v = modes.normalised_shapes[:6, j]
            still = [f"q{i + 1}" for i in range(6) if abs(v[i]) < 1e-6]
            out.append("rigid body (shift at constant belt length)"
                       + (f"; {', '.join(still)} still" if still else "; all q~ equal"))
            continue
        order = np.argsort(-np.abs(e[j]))
        parts = [f"{names[i]} {abs(e[j, i]):.0%}" for i in order if abs(e[j, i]) >= 0.1]
        out.append(", ".join(parts))
    return out


def fig4_5(params: Params) -> ModeFigure:
    """Figs. 4 and 5: actuation mode shapes and modal energy at r_g = 1, for the paper's
    Sec. 2.1 rows (whose characters the paper describes) and for the machine.

    Parameters
    ----------
    params : Params
        The parameter set (e.g. `empact.load_params`).

    Returns
    -------
    ModeFigure
        The Sec. 2.1 rows' modes, the machine's, the mode characters of both and the claims.
    """
    modes = actuation_model(params, 1.0, kinematics=SEC21).modes()
    e = np.abs(modes.energy_fraction)
    V = modes.normalised_shapes
    rigid_ok = bool(modes.n_rigid == 1 and np.allclose(V[6:, 0], 0, atol=1e-9)
                    and np.allclose(V[:6, 0], 1, atol=1e-9))
    checks = {
        "one rigid-body mode with q~1..q~6 equal and q~7 = q~8 = 0":
            (rigid_ok, f"{modes.n_rigid} rigid-body mode(s); q~1..q~8 = "
                       + ", ".join(f"{x:.2f}" for x in V[:, 0])),
        "mode 2: q1 and q3 in the same direction":
            (bool(V[0, 1] * V[2, 1] > 0), f"q~1 = {V[0, 1]:.3f}, q~3 = {V[2, 1]:.3f}"),
        "mode 3: q1 and q3 opposite":
            (bool(V[0, 2] * V[2, 2] < 0), f"q~1 = {V[0, 2]:.3f}, q~3 = {V[2, 2]:.3f}"),
        "mode 4: the chain holds most of the potential energy":
            (bool(e[3, 1] >= 0.5), f"chain energy fraction {e[3, 1]:.3f} (>= 0.5)"),
        "mode 5: in-phase pulley translation, belt not strained":
            (bool(e[4, 2] <= 0.05), f"belt energy fraction {e[4, 2]:.3f} (<= 0.05)"),
        "mode 6: out-of-phase pulley translation, belt strained":
            (bool(e[5, 2] >= 0.2), f"belt energy fraction {e[5, 2]:.3f} (>= 0.2)"),
    }
    claims = _checks("fig4_5", "Sec. 2.1, Figs. 4-5", checks, reading=READING[SEC21])
    # the machine: what equal translation implies instead (model notes Sec. 5)
    mm = actuation_model(params, 1.0, kinematics=MACHINE).modes()
    em, Vm = np.abs(mm.energy_fraction), mm.normalised_shapes
    machine_checks = {
        "(machine) the rigid-body mode is a shift by the primary servo alone: q~2 = q~4 = 0, "
        "q~1 = q~3 = q~5 = q~6":
            (bool(mm.n_rigid == 1 and np.allclose(Vm[[1, 3], 0], 0, atol=1e-9)
                  and np.allclose(Vm[[0, 2, 4, 5], 0], 1, atol=1e-9)),
             "q~1..q~6 = " + ", ".join(f"{x:.2f}" for x in Vm[:6, 0])),
        "(machine) mode 3 is the worm mode: the worm decouples from belt and bearings at "
        "r_g = 1":
            (bool(em[2, 0] >= 0.95), f"worm energy fraction of mode 3 {em[2, 0]:.3f} (>= 0.95)"
                                     f", of mode 2 {em[1, 0]:.3f}"),
    }
    claims += _checks("fig4_5.machine", "Secs. 1 and 2.3 (the machine), Figs. 4-5",
                      machine_checks, reading=READING[MACHINE],
                      why="The machine's modes do not have this character.")
    chars = []
    for kin, md in ((SEC21, modes), (MACHINE, mm)):
        for j, text in enumerate(mode_characters(md)):
            chars.append([kin, j + 1, float(md.frequencies_hz[j]), text])
    return ModeFigure(modes, claims, machine=mm, characters=chars)


@dataclass(frozen=True)
class Fig6:
    """Servo torque -> servo angle responses at three damping levels (Fig. 6).

    Attributes
    ----------
    responses : tuple of FrequencyResponse
        One per level ("none", "moderate", "large"), the paper's Sec. 2.1 rows (the reading
        Fig. 6 belongs to).
    machine : tuple of FrequencyResponse
        The machine's responses: undamped, moderate (Shafai) and moderate with the creep
        law linearised at ``params.operating`` as the pulley damping.
    slopes : dict of str to (float, float)
        ``{pair: (low, high)}`` log-log slopes [-] of the large-damping responses.
    f1_hz : float
        First elastic mode [Hz] (the slopes are taken at f1 / 20 and 30 f1).
    claims : tuple of Claim
        The checks.
    """

    responses: tuple[FrequencyResponse, ...]
    machine: tuple[FrequencyResponse, ...]
    slopes: dict[str, tuple[float, float]]
    f1_hz: float
    claims: tuple[Claim, ...]


def fig6(params: Params) -> Fig6:
    """Fig. 6: T_mp -> theta_mp and T_ms -> theta_ms with none / moderate / large damping
    (Sec. 2.1 rows), and the machine with Shafai's and the creep law's pulley damping.

    Parameters
    ----------
    params : Params
        The parameter set (e.g. `empact.load_params`).

    Returns
    -------
    Fig6
        The responses [rad/(N m)] of the Sec. 2.1 rows and of the machine, the slopes and the
        claims.
    """
    f = np.logspace(-1, 3.5, 800)
    w, pairs = 2 * np.pi * f, (["T_mp", "T_ms"], ["theta_mp", "theta_ms"])
    resps = tuple(actuation_model(params, 1.0, lvl, kinematics=SEC21).frequency_response(
        w, *pairs, label="undamped" if lvl == "none" else f"{lvl} damping")
        for lvl in DAMPING_LEVELS)
    op = params.operating.resolve(params)
    fm = np.logspace(-2, 3.5, 600)  # the creep law's integrator reaches below 0.1 Hz
    wm = 2 * np.pi * fm
    machine = (
        actuation_model(params, 1.0).frequency_response(wm, *pairs, label="undamped"),
        actuation_model(params, 1.0, "moderate").frequency_response(
            wm, *pairs, label="moderate (Shafai)"),
        actuation_model(params, 1.0, "moderate", op.omega_p, pulley_damping="creep",
                        F_s=op.F_s).frequency_response(
            wm, *pairs, label=f"moderate, creep law ({op.F_s / 1e3:g} kN, "
                              f"{op.omega_p:g} rad/s)"))
    large = resps[-1]
    f1 = float(actuation_model(params, 1.0, kinematics=SEC21).modes().frequencies_hz[1])
    slopes = {}
    for out, inp in (("theta_mp", "T_mp"), ("theta_ms", "T_ms")):
        mag = np.log10(np.abs(large.response(out, inp)))
        s = np.gradient(mag, np.log10(f))
        slopes[f"{inp} -> {out}"] = (float(s[np.argmin(abs(f - f1 / 20))]),
                                     float(s[np.argmin(abs(f - 30 * f1))]))
    ok = all(abs(lo + 1) < 0.1 and abs(hi + 2) < 0.1 for lo, hi in slopes.values())
    txt = "; ".join(f"{p}: {lo:.2f} at {f1 / 20:.2f} Hz, {hi:.2f} at {30 * f1:.0f} Hz"
                    for p, (lo, hi) in slopes.items())
    # the machine with the creep law: T_mp drives the shift against a velocity-proportional
    # resistance (slope -1), T_ms clamps against a spring (slope 0)
    mc = machine[2]
    ms = {}
    for out, inp in (("theta_mp", "T_mp"), ("theta_ms", "T_ms")):
        mag = np.log10(np.abs(mc.response(out, inp)))
        grad = np.gradient(mag, np.log10(fm))
        ms[f"{inp} -> {out}"] = float(grad[np.argmin(abs(fm - 0.02))])
        if inp == "T_mp":  # where the integrator gives way to the actuation's compliance
            corner = float(fm[np.argmax(grad > -0.5)])
    m_ok = abs(ms["T_mp -> theta_mp"] + 1) < 0.1 and abs(ms["T_ms -> theta_ms"]) < 0.1
    claims = (
        Claim(key="fig6.slopes", source="Sec. 2.1, Fig. 6",
              claim="with large damping both servo responses show a -1 slope at low and a "
                    "-2 slope at high frequency",
              computed=f"slopes (decades/decade, within 0.1): {txt}", shown=ok,
              explanation="Slopes of the large-damping magnitude at f1 / 20 and 30 f1.",
              reading=READING[SEC21], values={k: list(v) for k, v in slopes.items()}),
        Claim(key="fig6.machine_creep", source="Sec. 4 (-1 slope measured); issue 12",
              claim="(machine, creep law) T_mp -> theta_mp falls with -1 at low frequency (the "
                    "servo drives the shift against the belt's velocity-proportional creep "
                    "resistance); T_ms -> theta_ms is flat (the secondary servo clamps)",
              computed="slopes at 0.02 Hz: " + "; ".join(f"{k}: {v:+.2f}" for k, v in
                                                         ms.items())
                       + f" (within 0.1); the -1 slope of T_mp -> theta_mp ends (slope -0.5) "
                         f"at {corner:.2f} Hz",
              shown=m_ok, reading=READING[MACHINE],
              explanation="The machine's low-frequency slopes are not -1 and 0.",
              values={**ms, "corner_hz": corner}),
    )
    return Fig6(resps, machine, slopes, f1, claims)


def fig8(params: Params) -> ModeFigure:
    """Fig. 8: driveline mode shapes and modal energy at r_g = 1.

    Parameters
    ----------
    params : Params
        The parameter set (e.g. `empact.load_params`).

    Returns
    -------
    ModeFigure
        The driveline modes at r_g = 1 and the claims (``machine`` None, no ``characters``).
    """
    modes = driveline_model(params, 1.0).modes()
    e = np.abs(modes.energy_fraction)
    names = modes.springs
    checks = {
        "mode 2 mainly driveshaft": (bool(e[1].argmax() == 2),
                                     f"largest energy: {names[e[1].argmax()]} ({e[1].max():.2f})"),
        "mode 3 mainly torque converter": (bool(e[2].argmax() == 0),
                                           f"largest energy: {names[e[2].argmax()]} "
                                           f"({e[2].max():.2f})"),
        "mode 4 mainly pushbelt": (bool(e[3].argmax() == 1),
                                   f"largest energy: {names[e[3].argmax()]} ({e[3].max():.2f})"),
    }
    return ModeFigure(modes, _checks("fig8", "Sec. 2.2, Fig. 8", checks))
