"""Physical plausibility of a parameter set, beyond each value's own range.

`check_plausible` builds the models a parameter set defines and refuses the set, with one
line naming the file, the section or key and what is wrong, when:

* the ``[operating]`` point is outside what the models accept (a slip outside the traction
  curve's valid range, no clamping force);
* a linear model (actuation, driveline) at the smallest, medium and largest ratio has
  non-finite matrices, not exactly its expected rigid-body modes (one each), or elastic
  frequencies that are not finite and positive; with stiffnesses or inertias that span more
  than double precision resolves, extra "rigid-body" modes appear: the message names the
  extreme keys;
* the traction curve is not finite over its valid slip range.

`empact params validate` and every command that reads a parameter file run it, so a file that
validates is one every command accepts.
"""
from __future__ import annotations

import numpy as np

from .errors import ParameterError
from .linear.actuation import actuation_model
from .linear.driveline import driveline_model
from .params import Params, check_clamping
from .variator.geometry import ratio_range
from .variator.traction import traction_from_params

__all__ = ["check_plausible", "EXPECTED_RIGID_MODES"]

#: rigid-body modes of each linear model (the actuation's shift, the driveline's rotation)
EXPECTED_RIGID_MODES = {"actuation": 1, "driveline": 1}


def _extremes(section, names: tuple[str, ...]) -> str:
    values = {n: getattr(section, n) for n in names}
    hi = max(values, key=lambda n: values[n])
    lo = min(values, key=lambda n: values[n])
    return (f"largest {section._name}.{hi} = {values[hi]:g}, smallest {section._name}.{lo} = "
            f"{values[lo]:g}")


def check_plausible(params: Params, source: str = "parameters") -> Params:
    """Return `params` if every model it defines is plausible, else raise `ParameterError`.

    Parameters
    ----------
    params : Params
        The parameter set.
    source : str
        The file it came from (named in the message).

    Returns
    -------
    Params
        `params` itself, unchanged.

    Raises
    ------
    ParameterError
        One line naming `source`, the section or key and what is wrong (the module notes
        list the checks).
    """
    where = f"{source}: "
    tr = traction_from_params(params)
    try:  # a point given by a torque ratio or a load: its slip and clamping force solved
        params.operating.resolve(params, tr)
    except ParameterError as exc:
        raise ParameterError(f"{where}[operating] {exc}") from None
    lo, hi = tr.nu_range
    op = params.operating
    if op.nu is not None and not lo <= op.nu <= hi:
        raise ParameterError(f"{where}operating.nu = {op.nu:g}: outside the valid slip range "
                             f"[{lo:g}, {hi:g}] of the traction curve")
    if op.F_s is not None:
        check_clamping("operating.F_s", op.F_s, where=source)
    nu = np.linspace(lo, hi, 41)
    r_lo, r_hi = ratio_range(params.variator)
    ratios = sorted({r_lo, 1.0, r_hi} if r_lo <= 1.0 <= r_hi else {r_lo, r_hi})
    if not np.all(np.isfinite(tr.mu(nu[:, None], np.array(ratios)[None, :]))):
        raise ParameterError(f"{where}[traction]: the traction curve is not finite over its "
                             f"slip range [{lo:g}, {hi:g}]")
    checks = (("actuation", actuation_model, params.actuation,
               ("k_w", "k_c", "k_belt", "k_tp", "k_ts")),
              ("driveline", driveline_model, params.driveline, ("k_tc", "k_belt", "k_ds")))
    for name, build, section, stiff in checks:
        for r in ratios:
            lm = build(params, r)
            if not (np.all(np.isfinite(lm.M)) and np.all(np.isfinite(lm.K))):
                raise ParameterError(f"{where}[{name}]: the model at r_g = {r:.4g} has non-finite "
                                     f"mass or stiffness matrices")
            modes = lm.modes()
            f = modes.frequencies_hz
            expected = EXPECTED_RIGID_MODES[name]
            if modes.n_rigid != expected:
                raise ParameterError(
                    f"{where}[{name}]: the model at r_g = {r:.4g} has {modes.n_rigid} rigid-body "
                    f"modes, expected {expected}: stiffnesses and inertias span more than double "
                    f"precision resolves ({_extremes(section, stiff)})")
            elastic = f[modes.n_rigid:]
            if not np.all(np.isfinite(elastic) & (elastic > 0)):
                raise ParameterError(f"{where}[{name}]: the model at r_g = {r:.4g} has elastic "
                                     "frequencies that are not finite and positive")
    return params
