"""Figures (`empact.plotting`): every function draws into the caller's axes and returns a
`Plot` with its artists; one style; atomic saving."""
import inspect

import numpy as np
import pytest
from matplotlib.figure import Figure

from empact import plotting
from empact.linear.actuation import actuation_model
from empact.nonlinear.nmp import nmp_analysis
from empact.nonlinear.scenario import example_path, load_scenario
from empact.nonlinear.simulation import run_scenario
from empact.params import OperatingPoint
from empact.slip import (
    belt_root_locus,
    pole_sweep,
    slip_frequency_responses,
    stability_map,
    zero_locus,
)
from empact.variator.traction import traction_curves, traction_from_params


@pytest.fixture(scope="module")
def results(params):
    op = OperatingPoint(r_g=1.0, nu=0.01, F_s=1e4, omega_p=300.0)
    modes = actuation_model(params, 1.0).modes()
    resp = actuation_model(params, 1.0, "moderate").frequency_response(
        2 * np.pi * np.logspace(0, 2, 50), ["T_mp"], ["theta_mp"], label="moderate")
    sc = load_scenario(example_path("servo-torque-steps")).with_duration(0.05)
    return {
        "modes": modes, "resp": resp,
        "locus": belt_root_locus(params, 1.0, c_b_range=(1e-2, 1e2)),
        "curves": traction_curves(traction_from_params(params), [0.5, 1.0], [0.0, 0.01, 0.05]),
        "sweep": pole_sweep(params, "nu", [0.01, 0.02], op),
        "slip_resp": slip_frequency_responses(params, [op], 2 * np.pi * np.array([1.0, 10.0])),
        "zeros": zero_locus(params, [0.5, 1.0, 2.0], op),
        "map": stability_map(params, "nu", [0.01, 0.05], "r_g", [0.8, 1.2], base=op),
        "nmp": nmp_analysis(params, [0.5, 2.0]),
        "sim": run_scenario(sc, params),
    }


CASES = [
    ("plot_mode_shapes", lambda r: (r["modes"],), {}, (1, 1)),
    ("plot_modal_energy", lambda r: (r["modes"],), {}, (1, 1)),
    ("plot_bode", lambda r: ([r["resp"]], [("theta_mp", "T_mp")]), {}, (2, 1)),
    ("plot_belt_root_locus", lambda r: (r["locus"],), {}, (1, 1)),
    ("plot_traction", lambda r: (r["curves"],), {}, (1, 2)),
    ("plot_pole_sweep", lambda r: (r["sweep"],), {}, (1, 1)),
    ("plot_slip_bode", lambda r: (r["slip_resp"],), {}, (2, 1)),
    ("plot_zero_locus", lambda r: (r["zeros"],), {}, (1, 2)),
    ("plot_stability_map", lambda r: (r["map"],), {}, (1, 1)),
    ("plot_nmp", lambda r: (r["nmp"],), {}, (1, 2)),
    ("plot_simulation", lambda r: (r["sim"],), {}, (3, 2)),
]


@pytest.mark.parametrize("name, args, kw, shape", CASES, ids=[c[0] for c in CASES])
def test_draws_into_given_axes_and_returns_artists(results, name, args, kw, shape):
    fn = getattr(plotting, name)
    fig = Figure()
    axes = fig.subplots(*shape, squeeze=False)
    key = "ax" if "ax" in inspect.signature(fn).parameters else "axes"
    plot = fn(*args(results), **kw, **{key: axes[0, 0] if shape == (1, 1) else axes})
    assert isinstance(plot, plotting.Plot) and plot.figure is fig
    assert len(plot.artists) > 0
    # every drawn axes has a y label, and the bottom one of each column an x label
    for ax in fig.axes:
        if ax.get_visible() and ax.has_data() and ax.get_label() != "<colorbar>":
            assert ax.get_ylabel(), (name, ax.get_title())
            spec = ax.get_subplotspec()
            if spec is None or spec.is_last_row() or not axes[-1, spec.colspan.start].get_visible():
                assert ax.get_xlabel(), (name, ax.get_title())
    new = fn(*args(results), **kw)  # and without axes: a new figure of its own
    assert new.figure is not fig and new.axes.shape == shape


def test_symbols_and_save(tmp_path, results):
    assert plotting.symbol("T_mp") == r"$T_\mathrm{mp}$"
    assert plotting.symbol("omega_p") == r"$\omega_\mathrm{p}$"
    assert plotting.symbol("nu") == r"$\nu$"
    plot = plotting.plot_modal_energy(results["modes"])
    path = plot.save(tmp_path / "e.svg")
    assert path.stat().st_size > 1000 and list(tmp_path.iterdir()) == [path]
    with pytest.raises(ValueError, match="plot file suffix = 'gif'"):
        plot.save(tmp_path / "e.gif")


def _bode_like_figure():
    from empact.plotting._common import new_axes
    fig, axes = new_axes(None, 2, 2, size=(6.0, 4.0))
    f = np.logspace(-1, 3, 200)
    for ax in np.ravel(axes):
        ax.loglog(f, 1.0 / (1.0 + (f / 10.0) ** 4))  # 16 decades of magnitude
        ax.grid(True, which="both")
        ax.set_title(plotting.symbol("T_mp") + " -> " + plotting.symbol("nu"))
        ax.set_xlabel("frequency [Hz]")
    return fig, np.ravel(axes)


def test_save_lays_out_once_and_keeps_the_layout(tmp_path, monkeypatch):
    """Several formats: constrained layout runs in the first format's save only (one layout
    pass, then one draw per format), and the later formats keep its axes positions."""
    from empact.plotting._common import _lighten_log_axes, save_figure
    fig, axes = _bode_like_figure()
    draws = []
    original = Figure.draw
    monkeypatch.setattr(Figure, "draw", lambda self, r: (draws.append(1), original(self, r)))
    save_figure(fig, tmp_path / "b", formats=("png", "svg", "pdf"))
    assert len(draws) == 3 + 1  # three outputs plus the first one's layout pass
    assert fig.get_layout_engine() is None
    # the frozen positions are those a fresh constrained layout gives (independent drawing)
    ref, ref_axes = _bode_like_figure()
    _lighten_log_axes(ref)
    ref.set_dpi(150)  # the dpi save_figure draws at
    ref.draw_without_rendering()
    for a, b in zip(axes, ref_axes):
        np.testing.assert_allclose(a.get_position().bounds, b.get_position().bounds,
                                   atol=1e-12)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["b.pdf", "b.png", "b.svg"]


def test_log_value_axes_over_four_decades_lose_minor_ticks(tmp_path):
    """Minor ticks thinned on log value axes spanning > 4 decades; frequency axes keep them
    (with labels off beyond two decades)."""
    import matplotlib.ticker as mt

    from empact.plotting._common import save_figure
    fig, axes = _bode_like_figure()
    save_figure(fig, tmp_path / "b", formats=("png",))
    for ax in axes:
        assert isinstance(ax.yaxis.get_minor_locator(), mt.NullLocator)
        assert not isinstance(ax.xaxis.get_minor_locator(), mt.NullLocator)
        assert isinstance(ax.xaxis.get_minor_formatter(), mt.NullFormatter)
        assert len(ax.xaxis.get_minorticklocs()) > 20


def test_log_tick_labels_are_plain_text_of_the_tick_values(tmp_path):
    """Log tick labels are plain text with superscripts (no mathtext) and read back as the tick
    locations, on a many-decade axis and on a sub-decade one (``2×10¹`` labels)."""
    from empact.plotting._common import save_figure
    fig, axes = _bode_like_figure()
    axes[0].set_xlim(12.0, 60.0)  # less than a decade: labels at non-decade ticks
    save_figure(fig, tmp_path / "b", formats=("png",))
    digits = str.maketrans("\u2070\u00b9\u00b2\u00b3\u2074\u2075\u2076\u2077\u2078\u2079\u207b",
                           "0123456789-")
    checked = 0
    for ax in axes:
        for axis in (ax.xaxis, ax.yaxis):
            for tick in axis.get_major_ticks() + axis.get_minor_ticks():
                text, loc = tick.label1.get_text(), tick.get_loc()
                if not text or not tick.label1.get_visible():
                    continue
                assert "$" not in text, text
                mant, _, exp = text.partition("10")
                value = float(mant.rstrip("\u00d7") or 1) * 10.0 ** int(exp.translate(digits))
                np.testing.assert_allclose(value, loc, rtol=1e-12)
                checked += 1
    assert checked > 20
