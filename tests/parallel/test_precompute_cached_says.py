"""`precompute` of a cached scene teaches (issue #42 item 1): it says that nothing was
solved, that `tengfield run` reads that file, and what would be solved (not only
"cached ... use --force")."""
from __future__ import annotations

import plate_model as fx

from tengfield import surrogate
from tengfield.cli import main
from tengfield.scene import load_scene


def test_a_cached_scene_says_what_precompute_would_do(tmp_path, capsys):
    scene = load_scene(None)
    table = surrogate.precompute(scene, solve=fx.plate_model_solve)
    path = surrogate.cache_path(scene, tmp_path)
    surrogate.write_table(path, table)
    assert main(["precompute", "--cache-dir", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert out.startswith("already cached, nothing solved: ")
    assert "`tengfield run` of this scene reads" in out
    assert "another geometry or other [field] settings is solved" in out
    assert "--force" in out
