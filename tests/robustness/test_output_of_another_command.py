"""``-o DIR`` holding another command's files is refused in one line, before any work,
and nothing in it is lost (issue #42 item 7: `tengfield dynamics -o <a run's dir>`
deleted the run's waveforms.csv and PNGs)."""
from __future__ import annotations

from tengfield.cli import main

SHORT = ["--set", "run.duration_s=0.8", "--no-plots"]


def test_dynamics_into_a_maps_directory_is_refused_and_keeps_it(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["map", "--frequency-hz", "10:20:2", "--amplitude-mm", "1:2:2", "--periods",
                 "30", "--jobs", "1", "--no-plots", "-o", str(out)]) == 0
    before = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()}
    capsys.readouterr()
    assert main(["dynamics", *SHORT, "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("tengfield: error: -o ")
    assert "`tengfield map`" in err[0] and "map.csv" in err[0] and "nothing was written" in err[0]
    after = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()}
    assert after == before
    assert not [p for p in out.iterdir() if p.name.startswith(".tengfield-staging")]


def test_the_same_command_again_replaces_its_own_set(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["dynamics", *SHORT, "-o", str(out)]) == 0
    assert main(["dynamics", *SHORT, "--set", "contact.restitution=0.5", "-o", str(out)]) == 0
    assert (out / "trajectory.csv").is_file()


def test_a_directory_of_other_files_is_written_into(tmp_path):
    """A directory tengfield did not write (no record of a command) stays usable."""
    out = tmp_path / "out"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    assert main(["dynamics", *SHORT, "-o", str(out)]) == 0
    assert (out / "notes.txt").read_text() == "mine" and (out / "trajectory.csv").is_file()
