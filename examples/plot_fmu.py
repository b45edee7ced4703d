"""
The machine as an FMU, run by FMPy
==================================

`empact fmu export` (here its API, :func:`empact.fmu.export_fmu`) writes the nonlinear
machine as an FMI 2.0 co-simulation unit with empact's Rosenbrock integrator inside; any FMI
importer runs it (Simulink, OpenModelica, Dymola, FMPy). Here FMPy validates the unit and
runs a step of the secondary servo's torque at a 1 ms communication step: a positive servo
torque opens the secondary sheave (the sign convention of :mod:`empact.nonlinear`), so the
clamping falls and the slip rises, as `empact simulate` gives them. The importing machine
needs Python with empact installed (docs: "The machine as an FMU").
"""
import tempfile
from pathlib import Path

import fmpy
import matplotlib.pyplot as plt
import numpy as np
from fmpy.validation import validate_fmu

import empact
from empact.fmu import export_fmu

folder = Path(tempfile.mkdtemp())
unit = export_fmu(folder / "machine.fmu", empact.load_params())
print("validation problems:", validate_fmu(str(unit)))

# %%
# The inputs' start values hold the starting point (the trim of the shipped ``[operating]``
# point); a repeated time in the input table is a step: +0.5 N m on the secondary servo at
# 0.1 s.
md = fmpy.read_model_description(str(unit))
start = {v.name: float(v.start) for v in md.modelVariables if v.causality == "input"}
T = start["T_ms"]
u = np.array([(0.0, T), (0.1, T), (0.1, T + 0.5), (0.4, T + 0.5)],
             dtype=[("time", float), ("T_ms", float)])
res = fmpy.simulate_fmu(str(unit), stop_time=0.4, step_size=1e-3, input=u,
                        output=["nu", "F_s"])
print(f"slip {100 * res['nu'][0]:.3f} % -> {100 * res['nu'][-1]:.3f} %, "
      f"clamping {res['F_s'][0]:.0f} N -> {res['F_s'][-1]:.0f} N")

fig, (a, b) = plt.subplots(2, 1, sharex=True, figsize=(6.4, 4.8), layout="constrained")
a.plot(res["time"], 100 * res["nu"])
a.set_ylabel("slip nu [%]")
b.plot(res["time"], res["F_s"] / 1e3)
b.set_ylabel("clamping F_s [kN]")
b.set_xlabel("time [s]")
fig.suptitle("A servo torque step through the FMU (FMPy, 1 ms steps)")
plt.show()
