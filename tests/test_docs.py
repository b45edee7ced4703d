"""Documentation habits (python-control's): every public name documented, a numpydoc
"Parameters" section on every public function, class and method that takes parameters, and
it names every parameter."""
import doctest
import importlib
import inspect
import io
import pkgutil
import re
from pathlib import Path

import pytest

import empact


def _public():
    for info in pkgutil.walk_packages(empact.__path__, "empact."):
        if any(part.startswith("_") for part in info.name.split(".")) \
                or info.name in empact.DEPRECATED_MODULES:
            continue
        mod = importlib.import_module(info.name)
        yield info.name, mod, None
        for name in getattr(mod, "__all__", []):
            yield info.name, mod, getattr(mod, name)


def test_public_modules_and_names_have_docstrings():
    missing = [f"{mod_name}.{getattr(obj, '__name__', obj)}" if obj is not None else mod_name
               for mod_name, mod, obj in _public()
               if (obj is None and not mod.__doc__)
               or ((inspect.isfunction(obj) or inspect.isclass(obj)) and not inspect.getdoc(obj))]
    assert missing == []


def _unnamed_parameters(obj) -> list[str]:
    """The parameters of `obj` its Parameters section does not name (none without one)."""
    doc = inspect.getdoc(obj) or ""
    m = re.search(r"Parameters\n-+\n(.*?)(\n\n[A-Z][a-z]+\n-+\n|\Z)", doc, re.S)
    if not m:
        return []
    section, bad = m.group(1), []
    for p in inspect.signature(obj).parameters.values():
        if p.name in ("self", "cls"):
            continue
        if p.kind in (p.VAR_POSITIONAL, p.VAR_KEYWORD):
            name = ("*" if p.kind == p.VAR_POSITIONAL else "**") + p.name
        else:
            name = p.name
        if not re.search(rf"(^|[\s,]){re.escape(name)}\b", section, re.M):
            bad.append(name)
    return bad


def test_parameters_sections_are_complete():
    """Where a docstring has a Parameters section, it names every parameter (functions and
    public methods)."""
    bad = [f"{mod_name}.{obj.__name__}: {name}" for mod_name, _, obj in _public()
           if inspect.isfunction(obj) for name in _unnamed_parameters(obj)]
    bad += [f"{q}: {name}" for q, f in _public_methods() for name in _unnamed_parameters(f)]
    assert bad == []


# --- numpydoc coverage and doctests (issue 24, item 3) ----------------------------------------

#: the main entry points: their Examples run as doctests here
DOCTESTED = ("load_params", "actuation_model", "driveline_model", "slip_model",
             "nonlinear_model", "plant", "plant_family", "design_pi", "design_hinf",
             "simulate", "run_closed_loop", "monte_carlo")


def _sections(obj) -> set[str]:
    return set(re.findall(r"^([A-Z][A-Za-z ]+)\n-{3,}\s*$", inspect.getdoc(obj) or "", re.M))


def _needs(obj) -> set[str]:
    """The numpydoc sections `obj` must have: Parameters when it takes any, Returns when a
    function returns something (a class's Attributes count as its Parameters)."""
    try:
        sig = inspect.signature(obj)
    except (TypeError, ValueError):
        return set()
    need = {"Parameters"} if [p for p in sig.parameters if p not in ("self", "cls")] else set()
    if inspect.isfunction(obj) and sig.return_annotation not in (None, "None"):
        need.add("Returns")
    return need


def _complete(obj) -> bool:
    have = _sections(obj)
    if inspect.isclass(obj) and "Attributes" in have:
        have.add("Parameters")
    if "Yields" in have:
        have.add("Returns")
    return _needs(obj) <= have


def _public_objects():
    """Every public function and class once, under the module that defines it."""
    seen = {}
    for _, mod, obj in _public():
        if (inspect.isfunction(obj) or inspect.isclass(obj)) \
                and getattr(obj, "__module__", "").startswith("empact"):
            seen.setdefault(id(obj), (f"{obj.__module__}.{obj.__qualname__}", obj))
    return sorted(seen.values(), key=lambda t: t[0])


#: the share of public functions and classes (331) with the numpydoc Parameters / Returns
#: sections they need: 24 % before issue 24 (80; of the 235 functions 14, 6 %), 100 % after it.
#: Keep it whole: a new public function or class comes with its sections.
COVERAGE_FLOOR = 1.0


def test_numpydoc_coverage_does_not_fall():
    objs = _public_objects()
    done = [q for q, o in objs if _complete(o)]
    share = len(done) / len(objs)
    missing = [q for q, o in objs if not _complete(o)]
    assert share >= COVERAGE_FLOOR, f"{len(done)} of {len(objs)} complete ({share:.0%}): {missing}"


def test_the_curated_namespace_is_fully_documented():
    """Every name of ``import empact`` has its Parameters and Returns sections."""
    missing = [n for n in empact.__all__
               if (inspect.isfunction(getattr(empact, n)) or inspect.isclass(getattr(empact, n)))
               and not _complete(getattr(empact, n))]
    assert missing == []


def _public_methods():
    """Every public method (its name not starting with ``_``; properties are attributes) of
    the public classes, once, under the class that defines it."""
    seen = {}
    for qual, cls in _public_objects():
        if not inspect.isclass(cls):
            continue
        for name, attr in vars(cls).items():
            f = attr.__func__ if isinstance(attr, (classmethod, staticmethod)) else attr
            if not name.startswith("_") and inspect.isfunction(f):
                seen.setdefault(id(f), (f"{qual}.{name}", f))
    return sorted(seen.values(), key=lambda t: t[0])


#: the share of public methods with parameters (85) whose docstring has a numpydoc Parameters
#: section: 8 % before issue 31 (7), 100 % after it.  A new public method comes with its
#: section (as functions and classes do, `COVERAGE_FLOOR`).
METHOD_COVERAGE_FLOOR = 1.0


def test_public_methods_have_parameters_sections():
    methods = [(q, f) for q, f in _public_methods() if "Parameters" in _needs(f)]
    done = [q for q, f in methods if "Parameters" in _sections(f)]
    missing = sorted(set(q for q, _ in methods) - set(done))
    assert len(methods) >= 80  # the walk found them (85 at issue 31)
    assert len(done) / len(methods) >= METHOD_COVERAGE_FLOOR, \
        f"{len(done)} of {len(methods)} methods have Parameters: {missing}"


@pytest.mark.parametrize("name", DOCTESTED)
def test_entry_point_examples_run_as_doctests(name):
    obj = getattr(empact, name)
    assert {"Parameters", "Returns", "Examples"} <= _sections(obj), _sections(obj)
    module = inspect.getmodule(obj)
    tests = doctest.DocTestFinder(recurse=False).find(obj, name, module, globs=vars(module).copy())
    assert tests and tests[0].examples, f"{name}: no example"
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    out = io.StringIO()
    for test in tests:
        runner.run(test, out=out.write)
    assert runner.failures == 0, out.getvalue()


# --- the site's hand-written pages (issue 31, item 7) -------------------------------------------

DOCS = Path(__file__).resolve().parents[1] / "docs"
README = DOCS.parent / "README.md"


def _literalincludes(rst: str) -> list[tuple[str, dict[str, str]]]:
    """Each ``.. literalinclude::`` of a page: its file and options."""
    out = []
    for m in re.finditer(r"^\.\. literalinclude:: (\S+)\n((?:   :[\w-]+:.*\n)*)", rst, re.M):
        opts = dict(re.findall(r"^   :([\w-]+):\s*(.*)$", m.group(2), re.M))
        out.append((m.group(1), opts))
    return out


def _included(text: str, opts: dict[str, str]) -> str:
    """What Sphinx's literalinclude shows of `text` with ``start-at`` and ``end-before``: from
    the first line containing the one to the next containing the other."""
    lines = text.splitlines()
    start = next(i for i, line in enumerate(lines) if opts["start-at"] in line)
    end = next(i for i in range(start + 1, len(lines)) if opts["end-before"] in lines[i])
    return "\n".join(lines[start:end])


def test_getting_started_shows_the_readme_tour():
    """``docs/getting_started.rst`` includes the README's quick start, its tour's commands
    (the block `tests/test_readme.py` runs) and its Python example, whole, and has no hand
    copy of a command or of code."""
    from readme_tour import python_examples

    page, text = (DOCS / "getting_started.rst").read_text(), README.read_text()
    assert "code-block" not in page and ">>>" not in page
    blocks = []
    for path, opts in _literalincludes(page):
        assert (DOCS / path).resolve() == README
        blocks.append(_included(text, opts))
    tour = text[text.index("## A short tour"):]
    quick = text[text.index("## Quick start"):]
    assert blocks == [re.search(r"```sh\n(.*?)\n```", quick, re.S).group(1),
                      re.search(r"```sh\n(.*?)\n```", tour, re.S).group(1),
                      python_examples(text)[0].rstrip("\n")]


def test_control_chapter_examples_run():
    """The examples of ``docs/control.rst`` run (doctests) and the chapter links every public
    module of `empact.control` to its API page."""
    text = (DOCS / "control.rst").read_text()
    test = doctest.DocTestParser().get_doctest(text, {}, "control.rst", str(DOCS), 0)
    assert len(test.examples) >= 10
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    out = io.StringIO()
    runner.run(test, out=out.write)
    assert runner.failures == 0, out.getvalue()
    import empact.control
    modules = {m.name for m in pkgutil.iter_modules(empact.control.__path__)
               if not m.name.startswith("_")}
    assert sorted(m for m in modules if f"empact.control.{m}" not in text) == []
    assert ":doc:`api/control`" in text


def test_every_snippet_is_run_checked_or_excluded_in_one_list():
    """Every code snippet of the README and of the site's pages (`readme_tour.snippets`) has
    its entry in `readme_tour.COVERAGE` (issue 35, item 3): run by the tour's runner (a shell
    or Python snippet), checked by a test that exists, or excluded with a reason; no entry
    names a snippet that is gone."""
    from readme_tour import COVERAGE, RUN, snippets

    found = snippets()
    keys = {s.key for s in found}
    assert [f"{s.source}:{s.line} {s.key[1]!r}" for s in found if s.key not in COVERAGE] == []
    assert [k for k in COVERAGE if k not in keys] == []
    assert [f"{s.source}:{s.line}" for s in found
            if COVERAGE[s.key] == (RUN,) and s.kind not in ("sh", "python")] == []
    tests = Path(__file__).resolve().parent
    for how in set(COVERAGE.values()):
        if how[0] == "checked" and "::" in how[1]:
            file, name = how[1].split("::")
            assert f"def {name}(" in (tests / file).read_text(), how
        elif how[0] == "excluded":
            assert len(how[1]) > 20, how  # a reason, not a word
    counts = {k: sum(COVERAGE[s.key][0] == k for s in found) for k in (RUN, "checked",
                                                                       "excluded")}
    assert counts[RUN] >= 5 and sum(counts.values()) == len(found), counts
