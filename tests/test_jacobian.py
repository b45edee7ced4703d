"""The exact Jacobian by forward mode (`_kernel._eval_tangent`, issue 23 item 1) against the
complex step (`_kernel._jacobian_cs`), the reference it replaces in the integrators, the
linearisation and the plant families.

Norm: for each of A, B, C, D and each column j, ``max_i |J_fm[i, j] - J_cs[i, j]| <= 1e-10 *
max_i |J_cs[i, j]|`` (relative to the column's scale; an all-zero column must be zero), and
entry by entry ``|J_fm - J_cs| <= 1e-8 |J_cs| + 1e-12 * column scale`` (measured: the column
norm up to 2e-13, the entries 4e-12 where terms cancel).  States: seeded random perturbations of
trimmed points over the operating range (ratios 0.45-2.2, primary speeds 150-400 rad/s, slip
up to past the traction peak), with sheave velocities (shifting: the creep law's rate term
and its tanh saturation), Coulomb friction, every state layout (`state_layout`: locked belt,
speed-controlled drive and load, ratio controller) and every shift law and table option,
and the vehicle driveline (road load and final drive through standstill).
"""
import numpy as np
import pytest

from empact.nonlinear import _batch as KB
from empact.nonlinear import _kernel as K
from empact.nonlinear import _tangent as KT
from empact.nonlinear.equilibrium import trim
from empact.nonlinear.model import nonlinear_model
from empact.params import OperatingPoint
from empact.variator.losses import LossMap
from empact.variator.shift_law import CreepMap
from empact.variator.thrust_ratio import TabulatedThrustRatio

COL_TOL = 1e-10

KMAP = TabulatedThrustRatio((0.5, 1.0, 2.0),
                            (np.array([-1.0, 0.0, 0.5, 1.0]), np.array([-0.5, 0.3, 1.0]),
                             np.array([0.0, 1.0])),
                            (np.array([0.7, 0.75, 0.9, 1.1]), np.array([0.9, 1.0, 1.1]),
                             np.array([1.4, 1.2])), source="test")
CMAP = CreepMap((0.5, 1.0, 2.0), (np.array([5e3, 2e4]), np.array([5e3, 1e4, 3e4]),
                                  np.array([4e3, 2e4])),
                (np.array([1e-3, 2e-3]), np.array([2e-3, 2.5e-3, 4e-3]),
                 np.array([3e-3, 5e-3])), source="test")

#: a measured loss map over part of the operating range (the points leave it too: its held
#: values), curved in every variable: ``0.8 + 0.03 |T| + 2e-5 F / r + 4e-6 w^2`` [N m]
_LG = dict(r_g=np.array([0.5, 1.0, 2.0]), omega_in=np.array([100.0, 300.0, 500.0]),
           T_in=np.array([-20.0, 20.0, 80.0, 200.0]), F_s=np.array([4e3, 15e3, 40e3]))
_LM = np.meshgrid(*_LG.values(), indexing="ij")
LMAP = LossMap(**_LG, T_loss=0.8 + 0.03 * np.abs(_LM[2]) + 2e-5 * _LM[3] / _LM[0]
               + 4e-6 * _LM[1] ** 2, source="test")

#: model options: every state layout, every shift law, tables, friction
CASES = {
    "traction": dict(),
    "locked": dict(belt="locked"),
    "drive-speed": dict(drive="speed"),
    "load-speed": dict(load="speed", coulomb_sp=0.1),
    "all-loops": dict(drive="speed", load="speed", ratio_control=True, coulomb_sp=0.2,
                      coulomb_ss=0.1),
    "locked-loops": dict(belt="locked", drive="speed", load="speed", ratio_control=True),
    "ide": dict(shift_law="ide", ratio_control=True, coulomb_ss=0.05),
    "shafai": dict(shift_law="shafai", ratio_control=True, damping="large", coulomb_sp=0.1,
                   coulomb_ss=0.1),
    "shafai-torque": dict(shift_law="shafai", damping="none"),
    "tables": dict(thrust_ratio=KMAP, creep_map=CMAP, ratio_control=True),
    "loss-map": dict(loss_map=LMAP, drive="speed", ratio_control=True),
    "loss-map-locked": dict(loss_map=LMAP, belt="locked"),
    "vehicle": dict(driveline="vehicle"),
    "vehicle-locked-ratio": dict(driveline="vehicle", belt="locked", ratio_control=True,
                                 coulomb_sp=0.1),
}


def _pair(m, x, u, p=None):
    """(forward mode, complex step) A, B, C, D at (x, u), and the values of both routes."""
    p = m.p if p is None else p
    n = m.n
    fm = [np.empty((n, n)), np.empty((n, 4)), np.empty((K.NY, n)), np.empty((K.NY, 4))]
    cs = [np.empty_like(a) for a in fm]
    KT._jacobian(x, u, p, m.ix, *fm)
    K._jacobian_cs(x, u, p, m.ix, *cs)
    return fm, cs


def _check(fm, cs, label):
    for a, b, name in zip(fm, cs, "ABCD"):
        assert np.all(np.isfinite(a)), (label, name)
        col = np.abs(b).max(axis=0)
        err = np.abs(a - b).max(axis=0)
        bad = err > COL_TOL * col
        assert not bad.any(), (label, name, np.flatnonzero(bad), (err / (col + 1e-300)).max())
        ok = np.abs(a - b) <= 1e-8 * np.abs(b) + 1e-12 * col
        assert ok.all(), (label, name, np.argwhere(~ok)[:5])


def _points(m, rng, count):
    """Random states and inputs around trimmed points over the operating range."""
    out = []
    locked = m.options.belt == "locked"
    while len(out) < count:
        r = float(np.exp(rng.uniform(np.log(0.45), np.log(2.2))))
        w = float(rng.uniform(150.0, 400.0))
        if locked:
            op = OperatingPoint(r_g=r, omega_p=w, F_s=float(rng.uniform(6e3, 2e4)),
                                T_l=float(rng.uniform(5.0, 40.0)))
        else:
            op = OperatingPoint(r_g=r, omega_p=w, nu=float(rng.uniform(0.001, 0.01)),
                                F_s=float(rng.uniform(6e3, 2e4)))
        tr = trim(m, op)
        x = tr.x * (1 + 0.05 * rng.standard_normal(m.n)) + 1e-3 * rng.standard_normal(m.n)
        x[4:6] = tr.x[4:6] * (1 + 0.02 * rng.standard_normal(2))  # keep a belt geometry
        x[6:12] += rng.standard_normal(6) * np.array([20.0, 20.0, 5.0, 5.0, 3e-3, 3e-3])
        x[15] = w * (1 + 0.02 * rng.standard_normal())
        # the slip: from creep to past the traction peak (nu up to ~5 %), and backwards
        x[16] = x[15] * r * (1 - rng.uniform(-0.01, 0.05))
        u = tr.u * (1 + 0.1 * rng.standard_normal(4))
        out.append((x, u))
    return out


@pytest.mark.parametrize("name", list(CASES))
def test_forward_mode_equals_complex_step(params, name):
    """A, B, C, D and the values at seeded random states and inputs of every layout."""
    m = nonlinear_model(params, **CASES[name])
    rng = np.random.default_rng(23)
    for k, (x, u) in enumerate(_points(m, rng, 6)):
        fm, cs = _pair(m, x, u)
        _check(fm, cs, (name, k))
        # the values are the real evaluation's, bit for bit
        dx0, y0, dx1, y1 = np.empty(m.n), np.empty(K.NY), np.empty(m.n), np.empty(K.NY)
        K._eval(x, u, m.p, m.ix, dx0, y0)
        Sx, Su, Fd, Yd = KT._full_seeds(m.n, 4)
        KT._eval_tangent(x, u, m.p, m.ix, Sx, Su, dx1, y1, Fd, Yd)
        assert np.array_equal(dx0, dx1) and np.array_equal(y0, y1), (name, k)


@pytest.mark.parametrize("name", ["traction", "all-loops", "shafai", "tables", "loss-map"])
def test_outside_the_knots_and_saturated(params, name):
    """Ratios outside the traction curve's outer knots (its coefficients held constant), the
    creep law's tanh saturated by a fast shift, a pulley running backwards (|omega| branch)."""
    m = nonlinear_model(params, **CASES[name])
    rng = np.random.default_rng(5)
    x, u = _points(m, rng, 1)[0]
    tb = K.constants(m.p).tan_beta
    c = K.constants(m.p)
    for q5, q6, v in ((-0.004, 0.0, 0.5), (0.0, -0.004, -0.5), (0.001, 0.001, 5.0)):
        z = x.copy()
        z[4] = q5 + (c.R_max - c.R_min) * tb * 0.5 if q5 == 0.0 else q5
        z[5] = q6 + (c.R_max - c.R_min) * tb * 0.5 if q6 == 0.0 else q6
        z[10], z[11] = v, -v
        R_p = c.R_min + z[4] / tb
        R_s = c.R_s0 - c.sheave_sense * z[5] / tb
        assert abs(R_p - R_s) < c.a and R_p > 0 and R_s > 0
        _check(*_pair(m, z, u), (name, q5, q6, v))
    if name == "shafai":
        z = x.copy()
        z[16] = -abs(z[16])  # the secondary pulley backwards: _sabs's other branch
        _check(*_pair(m, z, u), (name, "omega_s < 0"))


def test_vehicle_load_through_standstill(params):
    """The vehicle driveline's road load and final drive loss (`_kernel._vehicle_load`)
    where their smooth signs are not saturated: the load shaft near standstill, forwards and
    backwards, and the driveshaft torque near zero and negative (the wheels driving)."""
    m = nonlinear_model(params, **CASES["vehicle"])
    x, u = _points(m, np.random.default_rng(7), 1)[0]
    for wl, twist in ((0.2, 0.001), (-0.3, -0.002), (0.05, -0.05), (1.0, 0.3), (30.0, -0.2)):
        z = x.copy()
        z[17], z[13] = wl, twist
        _check(*_pair(m, z, u), ("vehicle", wl, twist))


@pytest.mark.parametrize("knot", ["ln_r_low", "ln_r_med", "ln_r_od"])
def test_on_a_knot_the_branch_of_the_complex_step(params, knot):
    """With the ratio exactly on a knot of the traction coefficients' interpolation, the
    forward mode takes the complex step's branch (the segment on the left)."""
    m = nonlinear_model(params, ratio_control=True)
    x, u = _points(m, np.random.default_rng(11), 1)[0]
    c = K.constants(m.p)
    R_p = c.R_min + x[4] / c.tan_beta
    R_s = c.R_s0 - c.sheave_sense * x[5] / c.tan_beta
    p = m.p.copy()
    i = K.PARAMETER_NAMES.index(knot)
    p[i] = np.log(R_p / R_s)  # the kernel's own lr: exactly on the knot
    order = [K.P_LLOW, K.P_LMED, K.P_LOD]
    if i != K.P_LOD:  # keep the knots increasing
        for j in order[order.index(i) + 1:]:
            p[j] = max(p[j], p[i] + 0.3 * (order.index(j) - order.index(i)))
    if i != K.P_LLOW:
        for j in order[:order.index(i)]:
            p[j] = min(p[j], p[i] - 0.3 * (order.index(i) - order.index(j)))
    _check(*_pair(m, x, u, p), knot)


def test_piecewise_helpers_at_their_samples():
    """The laws' piecewise-linear helpers (`empact.variator._laws.knots_at`, `table_at`, as
    the kernel calls them) at and between their knots and samples and outside: the real
    values equal the complex ones' real parts and the slopes the complex step's."""
    h = 1e-30
    knots = np.array([-0.8, 0.1, 0.8, 2.0, 3.0, 1.5])
    for lr in (-1.2, -0.8, -0.3, 0.1, 0.5, 0.8, 1.3):
        v, rise, run = K.law.knots_at(lr, knots, 0, 3, 3)
        z = K.law.knots_at(complex(lr, h), knots, 0, 3, 3)[0]
        assert v == z.real and rise / run == pytest.approx(z.imag / h, rel=1e-14, abs=1e-300)
    p = np.zeros(K.NP)
    tables = np.concatenate([KMAP.encode(), CMAP.encode()])
    p = np.concatenate([p, tables])
    base_k, base_c = K.NP, K.NP + len(KMAP.encode())
    for base, xs in ((base_k, (-1.5, -1.0, -0.6, -0.5, 0.0, 0.3, 0.5, 0.99, 1.0, 1.4)),
                     (base_c, (1e3, 4e3, 5e3, 8e3, 1e4, 2e4, 2.5e4, 3e4, 5e4))):
        for lr in (np.log(0.3), np.log(0.5), np.log(0.7), 0.0, np.log(1.5), np.log(2.0),
                   np.log(2.5)):
            for xv in xs:
                v, sx, sl = K.law.table_at(xv, lr, p, base)
                zx = K.law.table_at(complex(xv, h), lr + 0j, p, base)[0]
                zl = K.law.table_at(xv + 0j, complex(lr, h), p, base)[0]
                assert v == zx.real
                assert sx == pytest.approx(zx.imag / h, rel=1e-13, abs=1e-300)
                assert sl == pytest.approx(zl.imag / h, rel=1e-13, abs=1e-300)


@pytest.mark.parametrize("name", ["traction", "locked", "all-loops", "shafai", "vehicle"])
def test_integrator_routines_and_batch(params, name):
    """The integrators' routines (`_state_jacobian` on the varying columns and in full,
    `_input_direction`) and the families' `linearize_batch` against their complex-step
    references, at the same column norm."""
    m = nonlinear_model(params, **CASES[name])
    pts = _points(m, np.random.default_rng(2), 4)
    n = m.n
    for x, u in pts:
        for cols in (K.varying_columns(m.ix, m.p), np.arange(n)):
            A0, A1 = np.zeros((n, n)), np.zeros((n, n))
            KT._state_jacobian(x, u, m.p, m.ix, A0, cols)
            K._state_jacobian_cs(x, u, m.p, m.ix, A1, cols)
            _check([A0], [A1], (name, "cols"))
        for du in (np.zeros(4), np.array([1.0, -2.0, 30.0, 4.0])):
            o0, o1 = np.empty(n), np.empty(n)
            KT._input_direction(x, u, du, m.p, m.ix, o0)
            K._input_direction_cs(x, u, du, m.p, m.ix, o1)
            assert np.all(np.abs(o0 - o1) <= COL_TOL * np.abs(o1).max() + 0.0)
    X = np.array([x for x, _ in pts])
    U = np.array([u for _, u in pts])
    N = len(pts)
    fm = [np.empty((N, n)), np.empty((N, n, n)), np.empty((N, n, 4)), np.empty((N, K.NY, n)),
          np.empty((N, K.NY, 4))]
    cs = [np.empty_like(a) for a in fm]
    KB.linearize_batch(X, U, m.p, m.ix, *fm)
    KB.linearize_batch_cs(X, U, m.p, m.ix, *cs)
    assert np.array_equal(fm[0], cs[0])
    for k in range(N):
        _check([a[k] for a in fm[1:]], [b[k] for b in cs[1:]], (name, "batch", k))


def test_stale_numba_cache_is_dropped(tmp_path):
    """numba keys a cache on its function's own file: when any source of the folder is newer
    than the oldest index, every index and data file goes (the suite calls this first)."""
    import os

    from empact._compile import drop_stale_cache

    cache = tmp_path / "__pycache__"
    cache.mkdir()
    (tmp_path / "_kernel.py").write_text("")
    files = [cache / "a.nbi", cache / "a.1.nbc", cache / "b.nbi"]
    for f in files:
        f.write_text("")
    os.utime(tmp_path / "_kernel.py", (1000.0, 1000.0))
    for f in files:
        os.utime(f, (2000.0, 2000.0))
    assert drop_stale_cache(tmp_path) == 0 and all(f.exists() for f in files)
    os.utime(files[2], (500.0, 500.0))  # one index older than the source
    assert drop_stale_cache(tmp_path) == 3 and not any(f.exists() for f in files)
    assert drop_stale_cache(tmp_path) == 0  # nothing left to drop


def test_the_cache_depends_on_the_compiled_modules_and_what_they_import():
    """`compiled_sources`: the kernel's, integrators' and batches' modules with the modules
    they import from (the variator's laws and the tabulated traction law compiled in, the
    kernel's constants) make their cache stale; the trims, the model's set-up and the
    simulator's Python loop (imported by none of them) do not, so editing those costs no
    compile."""
    from pathlib import Path

    import empact
    from empact._compile import compiled_sources

    root = Path(empact.__file__).resolve().parent
    kernel = {p.relative_to(root).as_posix()
              for p in compiled_sources([root / "nonlinear" / "_rodas.py"])}
    assert {"nonlinear/_rodas.py", "nonlinear/_rosenbrock.py", "nonlinear/_kernel.py",
            "nonlinear/_tangent.py", "nonlinear/_constants.py", "variator/_laws.py",
            "variator/_compiled.py", "variator/_traction_table.py",
            "variator/_loss_table.py"} <= kernel
    assert not kernel & {"nonlinear/equilibrium.py", "nonlinear/simulation.py",
                         "nonlinear/model.py", "nonlinear/__init__.py", "variator/__init__.py"}
    loop = {p.relative_to(root).as_posix()
            for p in compiled_sources([root / "control" / "_loop_core.py"])}
    assert kernel | {"control/_law_core.py", "control/_loop_core.py", "control/_driver_core.py",
                     "nonlinear/_batch.py"} == loop
