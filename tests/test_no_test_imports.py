"""Test files share helpers through helper modules (tests/README.md), never by
importing another test file (issue #41)."""
import ast
from pathlib import Path

TESTS = Path(__file__).resolve().parent


def test_no_test_file_imports_another_test_file():
    found = []
    for path in sorted(TESTS.rglob("test_*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import)
                     else [node.module or ""] if isinstance(node, ast.ImportFrom) else [])
            for name in names:
                leaf = name.rsplit(".", 1)[-1]
                if leaf.startswith("test_") and leaf != path.stem:
                    found.append(f"{path.relative_to(TESTS)}:{node.lineno}: {name}")
    assert not found, found
