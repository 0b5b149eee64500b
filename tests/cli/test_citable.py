"""tengfield is citable (issue #42 item 8): LICENSE (MIT, as pyproject says),
CITATION.cff (CFF 1.2.0: the software and the reference article), the article named in
README and docs, and ``tengfield info`` naming the version and the git commit."""
from __future__ import annotations

import re
import subprocess
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
ARTICLE = "Electromechanical Energy Conversion in Bouncing Ball Triboelectric Nanogenerator"


def test_license_is_the_mit_license_pyproject_names():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert project["license"]["text"] == "MIT"
    text = (ROOT / "LICENSE").read_text()
    assert text.startswith("MIT License")
    assert "Permission is hereby granted, free of charge" in text
    assert 'THE SOFTWARE IS PROVIDED "AS IS"' in text


def test_citation_cff_is_cff_1_2_0_and_cites_software_and_article():
    yaml = pytest.importorskip("yaml")
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text())
    # CFF 1.2.0's required keys and types
    assert cff["cff-version"] == "1.2.0"
    assert isinstance(cff["message"], str) and cff["message"]
    assert cff["title"] == "tengfield" and cff["type"] == "software"
    assert cff["version"] == project["version"]
    assert cff["license"] == "MIT"
    for people in [cff["authors"], cff["preferred-citation"]["authors"]]:
        assert people and all(("name" in p) != ("family-names" in p) for p in people)
    article = cff["preferred-citation"] if cff["preferred-citation"]["type"] == "article" \
        else cff["references"][0]
    assert article["type"] == "article" and article["title"] == ARTICLE
    allowed = {"cff-version", "message", "title", "type", "version", "license", "authors",
               "abstract", "keywords", "references", "preferred-citation", "date-released",
               "repository-code", "url", "doi", "identifiers"}
    assert set(cff) <= allowed, set(cff) - allowed


def test_readme_and_docs_name_the_reference_article():
    def prose(path):      # a title may wrap
        return " ".join(path.read_text().split())

    assert ARTICLE in prose(ROOT / "README.md")
    assert any(ARTICLE in prose(p) for p in (ROOT / "docs").glob("*.md"))


def test_info_names_version_and_commit(run_cli):
    import tengfield

    proc = run_cli("info")
    assert proc.returncode == 0, proc.stderr
    lines = dict(re.split(r"\s{2,}", ln.strip(), maxsplit=1)
                 for ln in proc.stdout.splitlines() if re.search(r"\S\s{2,}\S", ln))
    assert lines["tengfield"] == tengfield.__version__
    head = subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True,
                          text=True).stdout.strip()
    if not (ROOT / ".git").exists():      # a copy of the tracked files (the CI's images)
        assert lines["git commit"] == "not a git checkout"
        return
    dirty = bool(subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"],
                                cwd=ROOT, capture_output=True, text=True).stdout.strip())
    assert lines["git commit"].split(",")[0] == head[:12]
    assert ("modified" in lines["git commit"]) == dirty


def test_info_outside_a_git_checkout(tmp_path, monkeypatch):
    """Installed from a wheel (no .git next to the package): 'not a git checkout'."""
    from tengfield.commands import info

    monkeypatch.setattr(info, "package_root", lambda: tmp_path)
    assert info.git_commit() == "not a git checkout"


def test_info_names_the_blas_the_factorisations_run_on(run_cli):
    """A bug report says which BLAS PETSc (CHOLMOD, MUMPS) and numpy loaded, with their
    threads: OpenBLAS on this stack (scripts/install-system.sh), one thread in the CLI."""
    proc = run_cli("info")
    assert proc.returncode == 0, proc.stderr
    blas = next(ln for ln in proc.stdout.splitlines() if ln.startswith("BLAS"))
    assert "openblas" in blas and "reference BLAS" not in blas
    assert "threads" not in blas          # "1 thread" each
