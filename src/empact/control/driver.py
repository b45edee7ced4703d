"""The driver in the loop: a speed-following driver model and the loop law that runs it with
the transmission's law (issue 34, items 2 and 4).

`Driver` follows a speed trace: a PI on the car's speed with the feedforward of the trace's
acceleration (times the car's effective mass at the measured ratio: the car, its rotating
parts, the pulleys and the engine reflected) and of the road load at the trace's speed; the
wheels' force demand goes to the engine (``F (r_w / i_fd) r_g / eta_fd``, at most its
full-load torque at its speed: the integral then stops growing) where it is positive, else
to the friction brakes (the engine at ``T_coast``, 0: no load, fuelled); no regeneration;
the engine's torque follows the demand with a first-order lag (``tau_engine``, 0.1 s).
Its gains follow a bandwidth: ``k_p = m_eff 2 pi f``, ``k_i = k_p 2 pi f / 4`` (``f``
`bandwidth_hz`, 0.5 Hz by default: a driver's, well below the transmission's loops).  A
user's driver is a `Driver` with other values (or a subclass packing other tables for the
same compiled sample).

`DrivenLaw` is the transmission's loop law (`empact.control.law.LoopLaw`) with the driver
beside it, both compiled into one sample loop (`empact.control._loop_core.run_samples_driven`:
no Python per sample): it commands ``T_mp, T_ms`` (the law) and ``T_d, T_l`` (the engine's
torque and the brakes, the driver).  Its references are given at knots (a drive cycle's
1 Hz samples, prepared in advance from the trace: `empact.dynamic_cycle`) and interpolated
linearly to the loop's samples; what the law computes of them (the slip set-point of a torque
ratio, its traction coefficient, the decoupler's torque ratio from a trim) is computed at the
knots and interpolated likewise, so that a 30-minute cycle at 1 kHz costs the knots' work,
not the samples'.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np
from numpy.typing import NDArray

from .._validate import check_number
from ..errors import ParameterError
from ..nonlinear.equilibrium import (
    slip_at_torque_ratio,
    smallest_slip_reserve,
    traction_peak,
    trim_grid,
)
from ..nonlinear.model import OUTPUTS, EmpactModel
from ..nonlinear.simulation import SampledLoop
from ..variator.geometry import ratio_range
from . import _driver_core as DC
from . import _loop_core
from .controller import Controller
from .law import LoopConfig, LoopLaw, _no_geometry, _Refs

__all__ = ["Driver", "DrivenLaw", "DRIVER_SIGNALS"]

#: what the driver reads besides the law's signals (model outputs; the compiled loop reads
#: them from the outputs directly)
DRIVER_SIGNALS = ("v", "omega_d")


@dataclass(frozen=True)
class Driver:
    """The driver model (module notes).

    Attributes
    ----------
    bandwidth_hz : float
        The speed loop's bandwidth [Hz] (``k_p = m_eff 2 pi f``, ``k_i = k_p 2 pi f / 4``).
    T_coast : float
        The engine's brake torque while the driver does not ask for traction [N m] (0: no
        load, fuelled at its friction: the quasi-static cycle's "no fuel cut").
    tau_engine : float
        The engine torque's lag behind its demand [s] (first order: the intake manifold's
        filling, about 0.1 s for a port-injected SI engine at part load; without it every
        knot of the trace's acceleration would step the torque).
    """

    bandwidth_hz: float = 0.5
    T_coast: float = 0.0
    tau_engine: float = 0.1

    def __post_init__(self) -> None:
        object.__setattr__(self, "bandwidth_hz", check_number(
            "driver.bandwidth_hz", self.bandwidth_hz, 0.0, 10.0, lo_open=True, unit="Hz"))
        object.__setattr__(self, "T_coast", check_number(
            "driver.T_coast", self.T_coast, -100.0, 100.0, unit="N m"))
        object.__setattr__(self, "tau_engine", check_number(
            "driver.tau_engine", self.tau_engine, 0.0, 2.0, lo_open=False, unit="s"))

    def pack(self, model: EmpactModel, t: NDArray, v: NDArray, dt: float,
             n_k: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The compiled driver's constants and table (`empact.control._driver_core`) for a
        trace on the loop's samples.

        Parameters
        ----------
        model : EmpactModel
            The car (``driveline = "vehicle"``).
        t, v : ndarray, shape (K,)
            The trace's times [s] (from the run's start) and speeds [m/s], linear between.
        dt : float
            The loop's sample period [s].
        n_k : int
            The loop's samples.

        Returns
        -------
        c : ndarray, shape (len(CONSTANTS),)
        tab : ndarray, shape (n_k, 2)
            The reference speed [m/s] and acceleration [m/s^2] at each sample (the trace's
            slope on its interval).
        """
        if not model.vehicle:
            raise ParameterError("the driver drives a car: the model needs driveline = "
                                 "'vehicle'")
        p, kc = model.params, model.constants
        veh, eng = p.vehicle, p.engine
        gear = veh.r_wheel / veh.i_fd
        m_car = veh.mass * (1 + veh.e_rot)
        w = 2 * np.pi * self.bandwidth_hz
        kp = m_car * w
        values = dict(m_eff=m_car, f0=veh.f0, f1=veh.f1, f2=veh.f2,
                      F_grade=kc.road_grade_force, gear=gear, eta_fd=veh.eta_fd, kp=kp,
                      ki=kp * w / 4, dt=dt, T_peak=eng.T_peak, omega_T=eng.omega_T,
                      c_full=eng.c_full, T_coast=self.T_coast, J_s=kc.J_s,
                      J_p=kc.J_d + kc.J_p,
                      lag=-float(np.expm1(-dt / self.tau_engine)) if self.tau_engine else 1.0)
        c = np.array([values[k] for k in DC.CONSTANTS])
        tk = np.arange(n_k) * dt
        slope = np.diff(v) / np.diff(t)
        j = np.clip(np.searchsorted(t, tk, side="right") - 1, 0, len(slope) - 1)
        tab = np.column_stack([np.interp(tk, t, v), slope[j]])
        return c, np.ascontiguousarray(tab)


class DrivenLaw(LoopLaw):
    """The loop law with the driver beside it (module notes): commands ``T_mp, T_ms`` (the
    law's) and ``T_d, T_l`` (the engine's torque and the brakes', the driver's).

    Parameters
    ----------
    controller, model, point, u0, config
        As `LoopLaw`'s (`model` the car; `point` with the engine's torque ``T_d``).
    references : dict name -> array (k, 2)
        ``r_g`` and ``tau`` at the same knots ``[[t, value], ...]`` (times from the run's
        start [s]).
    duration : float
        The run's length [s].
    driver : Driver
    trace : ndarray, shape (K, 2)
        The speed trace ``[[t, v], ...]`` [s, m/s] (from the run's start).
    """

    commands: tuple[str, ...] = ("T_mp", "T_ms", "T_d", "T_l")

    def __init__(self, controller: Controller, model: EmpactModel, point: Mapping[str, float],
                 u0: NDArray, config: LoopConfig, references: Mapping[str, NDArray],
                 duration: float, driver: Driver, trace: NDArray) -> None:
        if config.spec.torque_request != "off":
            raise ParameterError("a driven law has no torque request (the driver commands "
                                 "the engine)")
        if config.spec.reserve_ahead:
            raise ParameterError("a driven law has no reserve ahead (controller.reserve_ahead "
                                 "= false)")
        if set(references) != {"r_g", "tau"}:
            raise ParameterError("a driven law's references are r_g and tau at the same knots")
        super().__init__(controller, model, point, u0, config, references, duration)
        self.driver = driver
        trace = np.asarray(trace, float)
        self._drv_c, self._drv_tab = driver.pack(model, trace[:, 0], trace[:, 1], self.dt,
                                                 self.n_k)
        self._drv_z = np.array([0.0, self.point.get("T_d", 0.0)])
        self._drv_out = np.zeros(2)

    def _references(self, references: Mapping[str, NDArray]) -> _Refs:
        """The references at the loop's samples from their knots (module notes): ratio and
        slip set-point (of the torque ratio) linear between the knots, the traction
        coefficient and the decoupler's torque ratio computed at the knots; the slip
        set-point is checked below the traction peak at every knot."""
        model, t = self.model, self.t_k
        r_tab, tau_tab = (np.asarray(references[k], float) for k in ("r_g", "tau"))
        if r_tab.shape != tau_tab.shape or not np.array_equal(r_tab[:, 0], tau_tab[:, 0]):
            raise ParameterError("a driven law's r_g and tau references share their knots")
        tk, rk, tauk = r_tab[:, 0], r_tab[:, 1], tau_tab[:, 1]
        lo, hi = ratio_range(model.params.variator)
        if np.any((rk < lo) | (rk > hi)):
            bad = rk[(rk < lo) | (rk > hi)][0]
            raise ParameterError(f"references.r_g = {bad:g}: outside the variator's ratio "
                                 f"range [{lo:.4g}, {hi:.4g}]")
        slip_k = slip_at_torque_ratio(model, tauk, rk)
        reserve, j = smallest_slip_reserve(model, rk, slip_k)
        if not np.all(slip_k > 0) or not reserve > 0:
            k = int(np.flatnonzero(~(slip_k > 0))[0]) if not np.all(slip_k > 0) else int(j)
            nu_pk = float(traction_peak(model, rk[k])[0])
            raise ParameterError(f"slip set-point {slip_k[k]:g} at r_g = {rk[k]:g}: must lie "
                                 f"on the rising traction curve (0, {nu_pk:.4g})")
        mu_k = model.traction(slip_k, rk)
        r = np.interp(t, tk, rk)
        slip = np.interp(t, tk, slip_k)
        mu = np.interp(t, tk, mu_k)
        self._tau_ref = min(max(float(mu_k[0] / model.mu_max(rk[:1])[0]), 1e-3), 0.999)
        rdot = np.append(np.diff(r) / np.diff(t), 0.0) if len(t) > 1 else np.zeros_like(t)
        dec = np.zeros_like(t)
        if self.config.spec.decoupling:
            ru, inv = np.unique(rk, return_inverse=True)
            g = trim_grid(model, ru, self.point["omega_p"],
                          tau=np.full(ru.shape, self._tau_ref), F_s=self.point["F_s"])
            if not np.all(g.ok):
                bad = ru[~g.ok][0]
                raise ParameterError(f"decoupling: the machine does not trim at the reference "
                                     f"ratio {bad:g} ({g.reason[~g.ok][0]})")
            dec = np.interp(t, tk, (g.u[:, 0] / g.u[:, 1])[inv.ravel()])
        return _Refs(r_g=r, slip=slip, mu=mu, rdot=rdot, decoupling=dec, slip_lo=slip,
                     mu_lo=mu)

    @property
    def measured(self) -> tuple[str, ...]:
        """The law's signals (`LoopLaw.measured`), then `DRIVER_SIGNALS`."""
        return super().measured + DRIVER_SIGNALS

    def reset(self) -> None:
        """Back to the first sample at rest (the driver's integral zero)."""
        super().reset()
        if hasattr(self, "_drv_z"):
            self._drv_z[:] = (0.0, self.point.get("T_d", 0.0))

    def run_compiled(self, k0: int, k1: int, loop: SampledLoop, t: float, h: float,
                     filled: int, n_steps: int, n_rej: int) -> tuple[int, float, float, int,
                                                                     int, int, int]:
        """`LoopLaw.run_compiled` with the driver in the compiled loop
        (`empact.control._loop_core.run_samples_driven`).

        Parameters
        ----------
        k0, k1 : int
            The simulator's first sample and the one after the last.
        loop : SampledLoop
            The simulator's arrays and the integrator's arguments.
        t, h : float
            Time [s] and step size [s] the integrator continues from.
        filled, n_steps, n_rej : int
            Output samples filled, integration steps taken and rejected so far.

        Returns
        -------
        tuple
            ``(status, t, h, filled, n_steps, n_rej, k)``.
        """
        status, t, h, filled, n_steps, n_rej, k, done, err = _run_driven(
            k0, k1, self._law, self._z, self._z_spare, self._k, self._drv_c, self._drv_tab,
            self._drv_z, loop, t, h, filled, n_steps, n_rej)
        self._k += done
        if done % 2:
            self._z, self._z_spare = self._z_spare, self._z
        if err:
            raise _no_geometry(self._wk.meas[0])
        return status, t, h, filled, n_steps, n_rej, k

    def step(self, t: float, measured: NDArray[np.float64]) -> NDArray[np.float64]:
        """Commands ``[T_mp, T_ms, T_d, T_l]`` [N m] over ``[t, t + dt)``: the law's sample,
        then the driver's (the Python path of `run_compiled`).

        Parameters
        ----------
        t : float
            The sample time [s].
        measured : ndarray, shape (len(measured),)
            The measured signals at `t` in `measured` order (SI).
        """
        k = self._k
        super().step(t, measured)
        y = np.zeros(len(OUTPUTS))
        y[_Y_DRIVER] = measured[0], measured[-2], measured[-1]
        DC.driver_sample(self._drv_c, self._drv_tab, self._drv_z, y, k, self._drv_out)
        self._wk.u[2:] = self._drv_out
        return self._wk.u.copy()


#: the model outputs the driver's sample reads (ratio, car speed, engine speed)
_Y_DRIVER = [OUTPUTS.index(n) for n in ("r_g", "v", "omega_d")]
_run_driven: Any = _loop_core.run_samples_driven
