"""The Python examples of the manual run: every ```python block of README.md and docs/*.md is
executed from the repository's root, and each line that ends in a comment starting with
``True`` must be true. The pages' other claims are prose; these are checked."""

import ast
import io
import os
import re
import tokenize
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[3]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
BLOCK = re.compile(r"^```python\n(.*?)^```$", re.DOTALL | re.MULTILINE)


def blocks():
    """(page, line of the block's first statement, code) for every Python block."""
    found = []
    for page in PAGES:
        text = page.read_text(encoding="utf-8")
        for match in BLOCK.finditer(text):
            line = text.count("\n", 0, match.start(1)) + 1
            found.append((page.relative_to(ROOT), line, match.group(1)))
    return found


def claimed_true(code):
    """The lines whose comment says the expression on them is true."""
    lines = set()
    for token in tokenize.generate_tokens(io.StringIO(code).readline):
        if token.type == tokenize.COMMENT and token.string[1:].strip().startswith("True"):
            lines.add(token.start[0])
    return lines


def test_the_manual_has_python_examples():
    pages = {page for page, _, _ in blocks()}
    assert Path("docs/python.md") in pages, pages


@pytest.mark.parametrize(
    "page, first, code", blocks(), ids=[f"{page}:{line}" for page, line, _ in blocks()]
)
def test_the_example_runs_and_its_claims_hold(page, first, code, monkeypatch):
    if "scipy" in code:
        pytest.importorskip("scipy")
    if "import control" in code and not os.environ.get("CI"):
        # CI installs python-control (.ci/run) and runs these blocks; elsewhere it may be missing.
        pytest.importorskip("control")
    monkeypatch.chdir(ROOT)  # the pages name examples from the repository's root
    tree = ast.parse(code, filename=str(page))
    claims = claimed_true(code)
    namespace = {"__name__": "__docs__"}
    checked = 0
    for statement in tree.body:
        where = f"{page}:{first + statement.lineno - 1}"
        if isinstance(statement, ast.Expr) and statement.end_lineno in claims:
            value = eval(compile(ast.Expression(statement.value), where, "eval"), namespace)
            assert value is True, f"{where}: {ast.unparse(statement)} is {value!r}"
            checked += 1
        else:
            exec(compile(ast.Module([statement], type_ignores=[]), where, "exec"), namespace)
    assert checked == len(claims), f"{page}: a `# True` comment stands on no expression"
