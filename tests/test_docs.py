"""Documentation habits (python-control's): every public name documented, and a numpydoc
"Parameters" section names every parameter of its function."""
import importlib
import inspect
import pkgutil
import re

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


def test_parameters_sections_are_complete():
    """Where a docstring has a Parameters section, it names every parameter."""
    bad = []
    for mod_name, _, obj in _public():
        if not inspect.isfunction(obj):
            continue
        doc = inspect.getdoc(obj) or ""
        m = re.search(r"Parameters\n-+\n(.*?)(\n\n[A-Z][a-z]+\n-+\n|\Z)", doc, re.S)
        if not m:
            continue
        section = m.group(1)
        for p in inspect.signature(obj).parameters.values():
            if p.kind in (p.VAR_POSITIONAL, p.VAR_KEYWORD):
                name = ("*" if p.kind == p.VAR_POSITIONAL else "**") + p.name
            else:
                name = p.name
            if not re.search(rf"(^|[\s,]){re.escape(name)}\b", section, re.M):
                bad.append(f"{mod_name}.{obj.__name__}: {name}")
    assert bad == []
