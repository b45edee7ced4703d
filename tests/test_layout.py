"""The package layout: no import circles, no function-level imports outside the command line,
and a command line that starts without the heavy dependencies."""
import ast
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import empact

PKG = Path(empact.__file__).parent


def _modules():
    for path in sorted(PKG.rglob("*.py")):
        rel = path.relative_to(PKG.parent).with_suffix("")
        name = ".".join(rel.parts)
        yield (name[:-9] if name.endswith(".__init__") else name), path


def _resolve(name: str, node: ast.ImportFrom, is_pkg: bool) -> str:
    if not node.level:
        return node.module or ""
    parts = name.split(".")
    base = parts if is_pkg else parts[:-1]
    base = base[:len(base) - node.level + 1]
    return ".".join(base + ([node.module] if node.module else []))


def _graph():
    """Module -> the empact modules it imports, counting every import statement: module level,
    inside functions (the command line's lazy imports), under ``if TYPE_CHECKING:``."""
    graph = {}
    for name, path in _modules():
        tree = ast.parse(path.read_text())
        deps = set()
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                deps |= {a.name for a in node.names if a.name.startswith("empact")}
            elif isinstance(node, ast.ImportFrom):
                mod = _resolve(name, node, path.name == "__init__.py")
                if mod.startswith("empact"):
                    deps.add(mod)
                    deps |= {f"{mod}.{a.name}" for a in node.names}
        graph[name] = deps
    names = set(graph)
    return {k: {d for d in v if d in names and d != k} for k, v in graph.items()}


def test_no_import_circles():
    """No circle of imports of any kind (module level, function level, TYPE_CHECKING)."""
    graph = _graph()
    # a package's __init__ re-exporting its submodules is not a circle of concepts: drop the
    # edges from a package to its own submodules and from submodules to their own package
    for k in graph:
        graph[k] = {d for d in graph[k] if not d.startswith(k + ".") and not k.startswith(d + ".")}
    seen, stack, cycles = {}, [], []

    def visit(n):
        seen[n] = 1
        stack.append(n)
        for d in graph[n]:
            if seen.get(d) == 1:
                cycles.append(stack[stack.index(d):] + [d])
            elif d not in seen:
                visit(d)
        stack.pop()
        seen[n] = 2

    for n in sorted(graph):
        if n not in seen:
            visit(n)
    assert cycles == []


def test_no_function_level_imports_outside_the_cli():
    bad = []
    for name, path in _modules():
        if name.startswith("empact.cli"):
            continue  # the command line loads each command's dependencies when it runs
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                for sub in ast.walk(node):
                    if isinstance(sub, (ast.Import, ast.ImportFrom)):
                        bad.append(f"{name}:{sub.lineno}")
    assert bad == []


def _loaded(*args):
    code = ("import sys, json; from empact.cli import main\n"
            "try:\n    main(%r, standalone_mode=False)\nexcept SystemExit:\n    pass\n"
            "print(json.dumps(sorted(k for k, m in sys.modules.items()\n"
            "                        if type(m).__name__ != '_LazyModule')))" % (list(args),))
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout
    return set(json.loads(out.strip().splitlines()[-1]))


def test_cli_start_up_imports_only_what_the_command_needs():
    heavy = {"matplotlib.pyplot", "scipy.stats", "control", "numba", "matplotlib",
             "scipy.signal", "scipy.optimize"}
    for args in (["--help"], ["params", "show"]):
        assert _loaded(*args) & heavy == set(), args
    # a figure-free analysis command loads neither pyplot nor scipy.stats, nor scipy.optimize
    # (a third of its start-up, for calls it does not make; a lazy module not yet used is not
    # loaded)
    assert _loaded("modes", "driveline") & {"matplotlib.pyplot", "scipy.stats",
                                            "scipy.optimize", "control"} == set()


def test_figures_of_linear_analyses_and_records_load_no_model(tmp_path):
    """`empact.plotting` imports a submodule when one of its names is first used: a Bode plot
    of the actuation model loads neither the nonlinear model (numba, ~0.5 s) nor the control
    layer; nor does an FRF estimate of measured records (``frf-estimate``'s module holds no
    experiment on the model)."""
    heavy = {"numba", "empact.nonlinear", "empact.control", "empact.experiments"}
    assert _loaded("frf", "actuation", "--input", "T_mp", "--output", "theta_mp", "--plot",
                   str(tmp_path / "frf.png")) & heavy == set()
    assert (tmp_path / "frf.png").stat().st_size > 1000
    t = np.arange(2048) / 100.0
    u = np.random.default_rng(1).standard_normal(t.size)
    np.savetxt(tmp_path / "rec.csv", np.column_stack([t, u, np.convolve(u, [0.5, 0.3])[:t.size]]),
               delimiter=",", header="time,u,y", comments="")
    assert _loaded("frf-estimate", str(tmp_path / "rec.csv"), "--input", "u", "--output", "y",
                   "--time", "time", "--json-out", str(tmp_path / "est.json")) & heavy == set()
    assert (tmp_path / "est.json").stat().st_size > 1000


def test_plotting_names_resolve_to_their_submodules():
    """Each public name of `empact.plotting` is its submodule's object (imported on first
    use), `dir` lists them, and an unknown name is an AttributeError."""
    import importlib

    import empact.plotting as plotting

    for name in plotting.__all__:
        module = importlib.import_module(f"empact.plotting.{plotting._CATALOGUE[name]}")
        assert getattr(plotting, name) is getattr(module, name), name
        assert name in module.__all__, name
    assert set(plotting.__all__) <= set(dir(plotting))
    with pytest.raises(AttributeError, match="plot_nothing"):
        plotting.plot_nothing  # noqa: B018


def test_linearize_and_nmp_do_not_import_python_control(tmp_path):
    """The exact plant's matrices and names need no python-control object (its import is
    ~1.5 s: `Plant.system` is built on first use): ``linearize`` (JSON and .mat) and ``nmp``
    load neither python-control nor ``scipy.signal``."""
    heavy = {"control", "scipy.signal", "scipy.stats", "matplotlib.pyplot"}
    assert _loaded("linearize", "--ratio", "1", "--tau", "0.9") & heavy == set()
    assert _loaded("linearize", "--ratio", "1", "--tau", "0.9", "--out",
                   str(tmp_path / "p.mat")) & heavy == set()
    assert (tmp_path / "p.mat").is_file()
    assert _loaded("nmp", "--ratios", "1", "--json") & heavy == set()


def test_control_commands_do_not_import_scipy_signal(tmp_path):
    """A controller is discretised without ``scipy.signal`` (0.9-1.5 s of start-up, with the
    ``scipy.stats`` it imports, for one ``cont2discrete`` call): `empact.lti.cont2discrete`."""
    from empact.control.pi import pi_controller

    pi_controller([2.0, 3.0], [0.5, 0.5], [10.0, 10.0]).save(tmp_path / "pi.json")
    loaded = _loaded("control", "discretize", str(tmp_path / "pi.json"), "--rate", "1000",
                     "--out", str(tmp_path / "pi_1khz.json"))
    assert (tmp_path / "pi_1khz.json").is_file()
    assert loaded & {"scipy.signal", "scipy.stats", "control"} == set()


def test_no_type_checking_imports():
    """Annotations name only what a module imports for real (no ``if TYPE_CHECKING:`` block
    hiding a dependency from the import graph)."""
    bad = [name for name, path in _modules() if "TYPE_CHECKING" in path.read_text()]
    assert bad == []


def test_the_kernel_stays_inside_nonlinear():
    """Only `empact.nonlinear` imports the compiled kernel and its integrators, the loop
    law's compiled sample (`empact.control._law_core`: the kernel's traction peak and creep
    law), the car driver's compiled sample (`empact.control._driver_core`: the kernel's
    output indices) and the compiled closed loop (`empact.control._loop_core`: the law's
    sample, the driver's and the integrator in one loop; the model must not import the
    control layer), which nothing but the loop law and the driven law
    (`empact.control.driver`) import; and the compile step (`empact._compile`, which calls every
    compiled entry point once, with the integrators' test problem `empact._stiff_linear`)."""
    graph = _graph()
    compiled = {"empact.nonlinear._kernel", "empact.nonlinear._tangent",
                "empact.nonlinear._batch", "empact.nonlinear._rosenbrock",
                "empact.nonlinear._rodas"}
    users = sorted(k for k, deps in graph.items()
                   if deps & compiled and not k.startswith("empact.nonlinear"))
    assert users == ["empact._compile", "empact._stiff_linear", "empact.control._driver_core",
                     "empact.control._law_core", "empact.control._loop_core"]
    assert sorted(k for k, deps in graph.items() if "empact.control._loop_core" in deps) == \
        ["empact.control.driver", "empact.control.law"]
