"""Test hygiene (issue 24, item 6), read from the test files themselves: every
`assert_allclose` states its tolerance, no assertion is over constants only (it could not
fail), and a test that pins today's results as a regression guard is named as one."""
import ast
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
