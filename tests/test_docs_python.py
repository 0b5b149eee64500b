"""Every ```python block of README.md and docs/*.md runs as a researcher would run it
(issue 53, docs/python.md; as scikit-fem's tests/test_examples.py runs its docs): a
file's blocks, concatenated in order, are one plain script (no ``__main__`` guard) run
by this interpreter from a fresh folder holding the ``my.toml`` and ``study.toml`` the
blocks load (the default scene with small run and field settings). It must exit 0
with no traceback and no warning on stderr.

A block whose first line is ``# docs-test: skip (reason)`` is not run (a fragment of
tengfield's own code, or a file a reader has and the test has not): the reason is
required, and every other block runs."""
import re
import subprocess
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[1]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
BLOCK = re.compile(r"^```python\n(.*?)^```", re.S | re.M)
SKIP = re.compile(r"#\s*docs-test:\s*skip\s*\((.+)\)")
#: a file's script (every block of it) must end within this
TIMEOUT_S = 900

#: the scene the blocks' ``tf.load_scene("my.toml")`` reads: the default device with
#: the small settings of HELPERS/tests (a run of ~1 s, a field solve of seconds)
SMALL_SCENE = """\
[run]
duration_s = 0.3
settle_periods = 2
sample_rate_hz = 5000

[field]
degree = 1
mesh_size_mm = 1.5
tolerance = 0.3
"""

#: docs/uncertainty.md's ``study.toml``: the small scene with a small study
STUDY_SCENE = SMALL_SCENE + """
[uncertainty]
samples = 16

[uncertainty.vary]
"contact.restitution" = { distribution = "uniform", low = 0.3, high = 0.6 }
"""


def python_blocks(path: Path) -> list[str]:
    """The ```python blocks of ``path`` in order, without those marked skip."""
    blocks = []
    for block in BLOCK.findall(path.read_text()):
        first = block.lstrip().splitlines()[0] if block.strip() else ""
        marked = SKIP.match(first.strip())
        if first.strip().startswith("# docs-test") and not marked:
            raise AssertionError(f"{path.name}: unknown marker {first!r}")
        if not marked:
            blocks.append(block)
    return blocks


WITH_BLOCKS = [p for p in DOCS if python_blocks(p)]


def test_the_docs_have_python_blocks_to_run():
    names = {p.name for p in WITH_BLOCKS}
    assert {"README.md", "pipeline.md", "dynamics.md"} <= names, names


@pytest.mark.parametrize("path", WITH_BLOCKS, ids=[p.name for p in WITH_BLOCKS])
def test_a_files_python_blocks_run_as_one_plain_script(path, python, cli_env, tmp_path):
    script = "\n\n".join(python_blocks(path))
    (tmp_path / "docs_script.py").write_text(script)
    (tmp_path / "my.toml").write_text(SMALL_SCENE)
    (tmp_path / "study.toml").write_text(STUDY_SCENE)
    env = cli_env(TENGFIELD_CACHE_DIR=tmp_path.parent / "docs-cache")
    done = subprocess.run([python, "docs_script.py"], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=TIMEOUT_S)
    assert done.returncode == 0, f"{path.name}:\n{done.stderr[-4000:]}"
    assert "Traceback" not in done.stderr, f"{path.name}:\n{done.stderr[-4000:]}"
    # a warning (VTK's "WARN| bad X server connection" too) is a defect of the example
    assert not re.search("warn", done.stderr, re.I), f"{path.name}:\n{done.stderr[-4000:]}"
