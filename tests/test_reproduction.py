"""The paper's claims as data (`empact.reproduction`): every claim the report checks, with its
verdict; the deviations from the paper are pinned by key."""
import json

import pytest

from empact.report.sections import SECTIONS
from empact.reproduction.claims import Claim

#: Claims the model does not reproduce, with the reason in the claim's explanation (README,
#: "Paper inconsistencies"); an unexpected failure or pass changes this set.
KNOWN_DEVIATIONS = {
    # Sec. 2.2: the uncoupled sides' labels (15.5 Hz primary, 24.6 Hz secondary) fit no
    # parameter set of Fig. 7 together with Table 2; empact uses them swapped
    "fig9.labels",
    # Secs. 2.3 and 3 on the machine with the creep law: eq. 2's slip has no real RHP zero at
    # any ratio, nu_r one at every ratio (the creep law separates the clamping transient from
    # the slow shift); with the Sec. 2.1 rows eq. 2's slip has one at every ratio
    "nmp.nu", "nmp.nu_r", "nmp.sec21",
    # Sec. 3 on Fig. 2: at the creep law's published magnitude the actuation modes move down
    # rather than gain much damping; the 48 Hz zeros lie just below their pole, not above it
    "fig2.damping", "fig2.zeros_48hz",
    # Sec. 4 / Fig. 14: the -1 slope of the servo angle ends near 0.35 Hz (creep law at its
    # published magnitude), and the machine's secondary servo clamps (flat T_ms -> theta_ms)
    "fig14.slope.T_mp", "fig14.slope.T_ms",
    # issue 13's closed-loop targets on the machine (beyond the paper): with slip control at
    # 1 % on the flat top of the shipped traction curve the load steps end in a slip limit
    # cycle, and the 1 /s shift at the creep law's published magnitude slackens the belt
    "control.slip-load-step-r0.5", "control.slip-load-step-r1", "control.slip-load-step-r2",
    "control.shift", "control.clamping_reduction",
}


CHEAP = ("table1", "table2", "fig4-5", "fig6", "fig8", "fig9", "fig10", "fig13")


@pytest.fixture(scope="session")
def claims(full_report):
    """Every claim, as the one full report build wrote them (claims.json: the records of
    `empact.reproduction`, one per claim, with their section)."""
    res, out = full_report
    assert res.exit_code == 0, res.output
    return json.loads((out / "claims.json").read_text())


def test_every_section_checks_claims(claims):
    keys = [c["key"] for c in claims]
    assert len(keys) == len(set(keys))  # unique keys
    assert {c["section"] for c in claims} == {s.anchor for s in SECTIONS}


@pytest.mark.parametrize("anchor", CHEAP)
def test_records_come_from_the_analysis(params, claims, anchor):
    """The analysis functions return the records the report wrote (same keys, verdicts)."""
    sec = next(s for s in SECTIONS if s.anchor == anchor)
    records = sec.compute(params).claims
    assert all(isinstance(c, Claim) for c in records)
    written = [(c["key"], c["shown"]) for c in claims if c["section"] == anchor]
    assert [(c.key, c.shown) for c in records] == written


def test_only_the_known_deviations_are_not_shown(claims):
    failed = {c["key"] for c in claims if not c["shown"]}
    assert failed == KNOWN_DEVIATIONS
    # every NOT-shown claim says why
    assert all(c["explanation"] for c in claims if not c["shown"])


def test_claim_needs_an_explanation_when_not_shown():
    with pytest.raises(ValueError, match="no explanation"):
        Claim(key="x", source="s", claim="c", computed="v", shown=False)
