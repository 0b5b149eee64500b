"""CI's split of the suite between the host (Debian 12) and the Debian 13 image (issue #41):
the host's ``make test`` runs ``-m "not image"``, the image ``make test-image`` runs
``-m "release or image"``; every test must be selected by at least one of them, and the
release-dependent ones by both."""
import ast
import itertools
import re
import subprocess
import sys
from pathlib import Path

TESTS = Path(__file__).resolve().parent
ROOT = TESTS.parent
HOST = "not image"
IMAGE = "release or image"


def _image_share():
    tree = ast.parse((TESTS / "conftest.py").read_text())
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(
                getattr(t, "id", None) == "IMAGE_SHARE" for t in node.targets):
            return ast.literal_eval(node.value)
    raise AssertionError("tests/conftest.py defines no IMAGE_SHARE")


MARKERS = ("release", "image", "slow", "field", "mpi")


def _combinations():
    """Every set of the suite's markers a test can carry (conftest never puts ``image``
    on a ``release`` test: checked below)."""
    for size in range(len(MARKERS) + 1):
        for markers in itertools.combinations(MARKERS, size):
            if not {"release", "image"} <= set(markers):
                yield markers


def _selected(tmp_path, expression: str) -> set:
    """The marker sets whose test ``pytest -m expression`` selects: pytest itself
    collects a generated file with one test per set (no private pytest API)."""
    lines = ["import pytest", ""]
    for k, markers in enumerate(_combinations()):
        lines += [f"@pytest.mark.{m}" for m in markers]
        lines += [f"def test_{k}():", "    pass", ""]
    (tmp_path / "test_markers.py").write_text("\n".join(lines))
    (tmp_path / "pytest.ini").write_text("[pytest]\nmarkers =\n" + "".join(
        f"    {m}: -\n" for m in MARKERS))
    out = subprocess.run([sys.executable, "-m", "pytest", "--collect-only", "-q", "-p",
                          "no:cacheprovider", "-c", str(tmp_path / "pytest.ini"),
                          "--rootdir", str(tmp_path), "-m", expression,
                          str(tmp_path / "test_markers.py")],
                         capture_output=True, text=True, cwd=tmp_path)
    assert out.returncode in (0, 5), out.stdout + out.stderr
    chosen = {int(k) for k in re.findall(r"::test_(\d+)$", out.stdout, re.M)}
    return {frozenset(m) for k, m in enumerate(_combinations()) if k in chosen}


def test_every_test_runs_on_one_release_and_the_release_dependent_ones_on_both(tmp_path):
    host = _selected(tmp_path, HOST)
    image = _selected(tmp_path, IMAGE)
    for markers in map(frozenset, _combinations()):
        assert markers in host or markers in image, set(markers)
        if "release" in markers:
            assert markers in host and markers in image, set(markers)
    # the expressions do select: the host leaves the image's share to the image
    assert frozenset({"image"}) not in host and frozenset({"image"}) in image
    assert frozenset() in host and frozenset() not in image


def test_conftest_marks_image_only_what_is_not_release_dependent():
    source = (TESTS / "conftest.py").read_text()
    assert re.search(r"if _is_release_dependent\(item\):\n\s+item.add_marker\(pytest.mark.release\)"
                     r"\n\s+elif _in_image_share\(item\):\n\s+item.add_marker\(pytest.mark.image\)",
                     source)


def test_the_ci_and_the_makefile_use_these_expressions():
    ci = (ROOT / ".ci" / "run").read_text()
    assert re.search(rf'^TEST_SELECT="{HOST}" make test </dev/null', ci, re.M), \
        "the host's make test in .ci/run"
    makefile = (ROOT / "Makefile").read_text()
    assert re.search(r'^test-serial:.*\n\t.*\$\(if \$\(TEST_SELECT\),-m "\$\(TEST_SELECT\)",\) tests$',
                     makefile, re.M)
    assert re.search(rf'^test-image-serial:.*\n\t.*-m "{IMAGE}" tests$', makefile, re.M)
    assert re.search(r"^test-image: setup test-image-serial test-mpi$", makefile, re.M)
    container = (ROOT / "scripts" / "test-container").read_text()
    assert 'MAKE_TEST_TARGET="${TENGFIELD_CONTAINER_MAKE_TARGET:-test-image}"' in container
    assert '[ "$SUITE" = trixie ]' in container     # the image that runs it by default


def test_every_entry_of_the_image_share_names_a_test_that_exists():
    share = _image_share()
    assert len(set(share)) == len(share)
    for entry in share:
        file, _, name = entry.partition("::")
        path = TESTS / file
        assert path.is_file(), entry
        source = path.read_text()
        if name:
            assert re.search(rf"^def {re.escape(name)}\(", source, re.M), entry
        else:
            assert re.search(r"^def test_", source, re.M), entry
