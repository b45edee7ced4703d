"""Write the API reference pages: one per subpackage (and per top-level module), each the
module's docstring and an autosummary table of its public names (`__all__`)."""
from __future__ import annotations

import importlib
import inspect
from pathlib import Path

#: page -> (title, modules whose __all__ it lists); in the order of the README's layout
PAGES = {
    "empact": ("empact: the curated namespace", ["empact"]),
    "params": ("Parameters and operating points",
               ["empact.params", "empact.operating", "empact.errors"]),
    "variator": ("empact.variator: geometry, traction, creep, thrust ratio",
                 ["empact.variator", "empact.variator.geometry", "empact.variator.traction",
                  "empact.variator.shift_law", "empact.variator.thrust_ratio",
                  "empact.variator.losses"]),
    "linear": ("empact.linear: actuation and driveline (Secs. 2.1-2.2)",
               ["empact.linear.lumped", "empact.linear.actuation", "empact.linear.driveline",
                "empact.linear.calibration"]),
    "slip": ("empact.slip: slip dynamics (Sec. 2.2, Figs. 9-13)",
             ["empact.slip.coupling", "empact.slip.model", "empact.slip.loci",
              "empact.slip.stability"]),
    "nonlinear": ("empact.nonlinear: the whole CVT (Secs. 2.3, 3)",
                  ["empact.nonlinear.model", "empact.nonlinear.options",
                   "empact.nonlinear.equilibrium",
                   "empact.nonlinear.linearization", "empact.nonlinear.nmp",
                   "empact.nonlinear.scenario", "empact.nonlinear.controller_spec",
                   "empact.nonlinear.simulation"]),
    "identification": ("empact.identification: realisation, FRF estimation, records",
                       ["empact.identification.realization",
                        "empact.identification.frf_estimation",
                        "empact.identification.records"]),
    "experiments": ("empact.experiments: Fig. 2 and the virtual rig (Fig. 14)",
                    ["empact.experiments.plant_id", "empact.experiments.rig"]),
    "control": ("empact.control: families, designs, robustness, the closed loop",
                ["empact.control.family", "empact.control.pi", "empact.control.hinf",
                 "empact.control.controller", "empact.control.robustness",
                 "empact.control.law", "empact.control.loop", "empact.control.closed_loop",
                 "empact.control.shifting", "empact.control.designs", "empact.control.tune"]),
    "montecarlo": ("empact.montecarlo: parameter spreads and studies",
                   ["empact.montecarlo.spread", "empact.montecarlo.analyses",
                    "empact.montecarlo.study", "empact.montecarlo.cycle", "empact.shards"]),
    "energy": ("Energy: actuation losses, the hydraulic reference, efficiency maps",
               ["empact.actuation_energy", "empact.efficiency"]),
    "vehicle": ("The car: drive cycles, vehicle, engine, the quasi-static and dynamic cycles",
                ["empact.cycles", "empact.vehicle", "empact.engine", "empact.drive_cycle",
                 "empact.dynamic_cycle", "empact.control.driver"]),
    "sweep": ("empact.sweep: in process or on Dask", ["empact.sweep"]),
    "lti": ("empact.lti: frequency responses, zeros, root loci", ["empact.lti"]),
    "export": ("empact.export: .mat and .npz", ["empact.export"]),
    "fmu": ("empact.fmu: the machine as an FMU (FMI 2.0)", ["empact.fmu"]),
    "plotting": ("empact.plotting: figures from result objects", ["empact.plotting"]),
    "reproduction": ("empact.reproduction: the paper's claims, checked",
                     ["empact.reproduction.claims", "empact.reproduction.linear",
                      "empact.reproduction.slip", "empact.reproduction.nonlinear",
                      "empact.reproduction.identification", "empact.reproduction.machine",
                      "empact.reproduction.control", "empact.reproduction.drive_cycle"]),
    "report": ("empact.report: the HTML report", ["empact.report"]),
    "other": ("The paper's numbers and plausibility checks",
              ["empact.paper", "empact.plausibility"]),
}


#: packages whose docstring is a plain-text catalogue (scipy's style, read by ``help()``)
CATALOGUES = ("empact", "empact.variator")


def _catalogue(modname: str) -> list[str]:
    """The catalogue as ``help()`` shows it, then a table linking each public name to its
    page."""
    mod = importlib.import_module(modname)
    doc = inspect.getdoc(mod) or ""
    lines = [f".. py:module:: {modname}", "", ".. code-block:: text", ""]
    lines += [f"   {ln}" if ln else "" for ln in doc.splitlines()] + [""]
    rows = []
    for name in getattr(mod, "__all__", []):
        obj = getattr(mod, name)
        home = getattr(obj, "__module__", "")
        if not home.startswith("empact") or not (inspect.isfunction(obj) or inspect.isclass(obj)):
            continue
        summary = (inspect.getdoc(obj) or "").split("\n\n")[0].replace("\n", " ")
        rows.append(f"   * - :obj:`{name} <{home}.{obj.__qualname__}>`\n     - {summary}")
    if rows:
        lines += [".. list-table::", "   :header-rows: 1", "   :widths: 25 75", "",
                  "   * - Name", "     - What it is"] + rows + [""]
    return lines


def _names(modname: str) -> list[str]:
    if modname == "empact":   # the catalogue: every name is documented on its module's page
        return []
    mod = importlib.import_module(modname)
    out = []
    for name in getattr(mod, "__all__", []):
        obj = getattr(mod, name)
        if inspect.isfunction(obj) or inspect.isclass(obj):
            # list a name where it is defined (a re-export is listed by its own module), or
            # under the package that re-exports it when its module has no place on any page
            # (empact.plotting's figures live in private-looking submodules of one concept)
            home = getattr(obj, "__module__", modname)
            if home == modname or (home.startswith(modname + ".") and home not in _LISTED):
                out.append(name)
    return out


#: every module that has its own heading on some page
_LISTED = {m for _, mods in PAGES.values() for m in mods}


def write_api_pages(folder: Path) -> list[str]:
    folder.mkdir(exist_ok=True)
    index = ["API reference", "=============", "",
             "One page per subpackage; every public function and class (a module's ``__all__``)",
             "with its numpydoc docstring. SI units throughout.", "", ".. toctree::",
             "   :maxdepth: 1", ""]
    for page, (title, modules) in PAGES.items():
        lines = [title, "=" * len(title), ""]
        for i, modname in enumerate(modules):
            if len(modules) > 1 or modname != "empact":
                lines += [modname, "-" * len(modname), ""]
            if modname in CATALOGUES:
                lines += _catalogue(modname)
            else:
                lines += [f".. automodule:: {modname}", "   :no-members:", ""]
            names = _names(modname)
            if names:
                lines += [f".. currentmodule:: {modname}", "", ".. autosummary::",
                          "   :toctree: generated", "   :nosignatures:", ""]
                lines += [f"   {n}" for n in names] + [""]
        text = "\n".join(lines)
        path = folder / f"{page}.rst"
        if not path.exists() or path.read_text() != text:
            path.write_text(text)
        index.append(f"   {page}")
    (folder / "index.rst").write_text("\n".join(index) + "\n")
    return list(PAGES)
