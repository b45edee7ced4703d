"""Test hygiene (issue 24, item 6), read from the test files themselves: every
`assert_allclose` states its tolerance, no assertion is over constants only (it could not
fail), a test that pins today's results as a regression guard is named as one, every
`pytest.approx` states its tolerance, and every module has its row in ``tests/MODULES.md``."""
import ast
import re
from pathlib import Path

TESTS = Path(__file__).resolve().parent


def _trees():
    for path in sorted(TESTS.glob("*.py")):
        yield path.name, ast.parse(path.read_text())


def test_every_assert_allclose_states_its_tolerance():
    missing = [f"{name}:{node.lineno}" for name, tree in _trees() for node in ast.walk(tree)
               if isinstance(node, ast.Call)
               and getattr(node.func, "attr", getattr(node.func, "id", "")) == "assert_allclose"
               and not {k.arg for k in node.keywords} & {"rtol", "atol"}]
    assert missing == []


def _vacuous(test: ast.expr) -> bool:
    """An assertion that cannot fail: no name in it at all (``assert 1 < 2``), or a
    comprehension whose element ignores its loop variable and every other name
    (``all(not math.isnan(0) for _ in rows)``)."""
    names = {n.id for n in ast.walk(test) if isinstance(n, ast.Name)}
    if not names:
        return True
    for comp in ast.walk(test):
        if isinstance(comp, (ast.GeneratorExp, ast.ListComp, ast.SetComp)):
            used = {n.id for n in ast.walk(comp.elt) if isinstance(n, ast.Name)}
            if not used - {"math", "np", "abs", "len", "float", "int", "str", "bool"}:
                return True
    return False


def test_no_assertion_is_over_constants():
    vacuous = [f"{name}:{node.lineno}: {ast.unparse(node.test)[:80]}"
               for name, tree in _trees() for node in ast.walk(tree)
               if isinstance(node, ast.Assert) and _vacuous(node.test)]
    assert vacuous == []


def test_the_checks_catch_what_they_are_for():
    assert _vacuous(ast.parse("all(not math.isnan(0) for _ in rows)", mode="eval").body)
    assert _vacuous(ast.parse("1 < 2", mode="eval").body)
    assert not _vacuous(ast.parse("all(r > 0 for r in rows)", mode="eval").body)


def test_regression_guards_are_named_as_such():
    """A test whose docstring calls it a regression guard (it pins the model's current
    numbers, not a reference) is named ``test_regression_*``, so that a failure reads as
    'the numbers moved', not 'the physics is wrong'."""
    misnamed = [f"{name}::{node.name}" for name, tree in _trees() for node in ast.walk(tree)
                if isinstance(node, ast.FunctionDef) and node.name.startswith("test_")
                and "regression guard" in (ast.get_docstring(node) or "").lower()
                and not node.name.startswith("test_regression_")]
    assert misnamed == []


def test_every_approx_states_its_tolerance():
    """``pytest.approx`` without ``rel=`` / ``abs=`` compares to 1e-6 relative silently: a
    test states the tolerance it means (and, beside it, the reference's source)."""
    missing = [f"{name}:{node.lineno}" for name, tree in _trees() for node in ast.walk(tree)
               if isinstance(node, ast.Call)
               and getattr(node.func, "attr", getattr(node.func, "id", "")) == "approx"
               and not {k.arg for k in node.keywords} & {"rel", "abs"}]
    assert missing == []


# --- the map of modules to their tests (issue 31, item 7) --------------------------------------

SRC = TESTS.parent / "src" / "empact"


def _modules() -> set[str]:
    names = set()
    for path in SRC.rglob("*.py"):
        parts = path.relative_to(SRC.parent).with_suffix("").parts
        names.add(".".join(parts[:-1] if parts[-1] == "__init__" else parts))
    return names


def _module_table() -> dict[str, list[str]]:
    """``tests/MODULES.md``: module -> its test files (rows ``| `module` | files |``)."""
    rows = {}
    for line in (TESTS / "MODULES.md").read_text().splitlines():
        m = re.match(r"\|\s*`([\w.]+)`\s*\|([^|]*)\|\s*$", line)
        if m:
            assert m.group(1) not in rows, f"MODULES.md: two rows for {m.group(1)}"
            rows[m.group(1)] = m.group(2).split()
    return rows


def test_every_module_has_its_tests_in_the_table():
    """Each module of ``src/empact`` has a row in ``tests/MODULES.md`` naming existing test
    files, and the table names no module that is gone."""
    table, modules = _module_table(), _modules()
    assert len(modules) > 50  # the walk found the package
    assert sorted(modules - set(table)) == [], "modules without a row in tests/MODULES.md"
    assert sorted(set(table) - modules) == [], "rows of tests/MODULES.md for no module"
    bad = [f"{mod}: {f}" for mod, files in table.items() for f in files or ["(none)"]
           if not re.fullmatch(r"test_\w+\.py", f) or not (TESTS / f).is_file()]
    assert bad == []


def test_the_approx_check_catches_a_bare_approx():
    bare = ast.parse("assert x == pytest.approx(1.0)").body[0].test.comparators[0]
    stated = ast.parse("assert x == pytest.approx(1.0, rel=1e-9)").body[0].test.comparators[0]
    assert not {k.arg for k in bare.keywords} & {"rel", "abs"}
    assert {k.arg for k in stated.keywords} & {"rel", "abs"}


def _split_references(text: str) -> list[int]:
    """Line numbers (1-based) where a single-backtick reference opens and does not close: a
    reference split across lines, which Sphinx -W refuses ("start-string without end-string")
    after the tests have passed."""
    return [i for i, line in enumerate(text.splitlines(), 1)
            if line.replace("``", "").count("`") % 2]


def test_no_reference_is_split_across_lines():
    """Every `name` reference in the package's source opens and closes on one line (the docs
    build failed on one in `monte_carlo`'s docstring, issue 31)."""
    bad = [f"{p.relative_to(SRC)}:{i}" for p in sorted(SRC.rglob("*.py"))
           for i in _split_references(p.read_text())]
    assert bad == []


def test_the_split_reference_check_catches_one():
    """The check fails on the shape it is for and passes its repair."""
    assert _split_references("x (`empact.variator.traction.\n    TabulatedTraction`) y") == [1, 2]
    assert _split_references("x\n    (`empact.variator.traction.TabulatedTraction`) ``a`` y") == []
