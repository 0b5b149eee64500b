"""The worker pools' fork server imports ``tengfield._pool_preload`` and ignores an
ImportError there (multiprocessing's preload), so a renamed module would silently stop
the preloading: every module it names must exist (``circuit.py`` and ``sweep.py`` were
renamed and it still named them)."""
import ast
import importlib.util
from pathlib import Path

PRELOAD = Path(__file__).resolve().parents[2] / "src" / "tengfield" / "_pool_preload.py"


def test_every_module_the_fork_server_preloads_exists():
    tree = ast.parse(PRELOAD.read_text())
    named = []
    for node in tree.body:
        if isinstance(node, ast.ImportFrom) and node.level == 1:
            base = "tengfield" + (f".{node.module}" if node.module else "")
            named += [f"{base}.{alias.name}" for alias in node.names]
    assert "tengfield.sweeps" in named and "tengfield.array" in named
    missing = [name for name in named if importlib.util.find_spec(name) is None]
    assert not missing, f"_pool_preload.py names modules that do not exist: {missing}"
