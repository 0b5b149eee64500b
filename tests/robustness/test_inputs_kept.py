"""#30 item 1: a file a command reads (its scene, a recorded excitation, fit's measured
trace) is never removed or replaced by that command's output set in -o DIR: replacing
it is refused with one line (nothing written), and the manifest clean-up keeps it."""
from pathlib import Path

import pytest

from tengfield.files import note_input
from tengfield.files.directory import OutputError, StagedOutput

SHORT = "[run]\nduration_s = 0.3\nsettle_periods = 2\nsample_rate_hz = 2000\n"
RECORDED = ('[excitation]\nkind = "recorded"\nfile = "trajectory.csv"\ntime_column = "time_s"\n'
            'signal_column = "table_m"\nsignal = "displacement"\n' + SHORT)


def write_set(target: Path, files: dict[str, str]) -> None:
    with StagedOutput(target) as staging:
        for name, text in files.items():
            (staging / name).write_text(text)


def test_stale_input_is_kept_by_the_manifest_clean_up(tmp_path):
    """fit --measured D/waveforms.csv -o D: waveforms.csv, written by the previous
    command and read by this one, is not removed as the previous set's leftover."""
    out = tmp_path / "D"
    write_set(out, {"waveforms.csv": "t,v\n", "summary.json": "{}"})
    with StagedOutput(out) as staging:
        note_input(out / "waveforms.csv")
        (staging / "fit.json").write_text("{}")
    assert (out / "waveforms.csv").read_text() == "t,v\n"
    assert not (out / "summary.json").exists()       # the rest of the old set goes
    assert (out / "fit.json").is_file()


def test_replacing_an_input_is_refused_and_nothing_written(tmp_path):
    out = tmp_path / "D"
    write_set(out, {"trajectory.csv": "input\n", "old.json": "{}"})
    staged = StagedOutput(out)
    staging = staged.open()
    note_input(out / "trajectory.csv")
    (staging / "trajectory.csv").write_text("output\n")
    (staging / "impacts.csv").write_text("x\n")
    with pytest.raises(OutputError, match=r"'trajectory.csv' there is a file this command read"):
        staged.commit()
    assert (out / "trajectory.csv").read_text() == "input\n"
    assert (out / "old.json").is_file() and not (out / "impacts.csv").exists()
    assert not list(out.glob(".tengfield-staging-*"))


def test_inputs_of_an_earlier_command_are_forgotten(tmp_path):
    """The list of inputs is per command: a file read by an earlier command is replaced."""
    out = tmp_path / "D"
    write_set(out, {"a.csv": "1\n"})
    note_input(out / "a.csv")
    write_set(out, {"a.csv": "2\n"})
    assert (out / "a.csv").read_text() == "2\n"


@pytest.mark.slow
def test_dynamics_never_overwrites_its_recorded_input(tmp_path, run_cli):
    """`dynamics s.toml -o .` with file = "trajectory.csv": refused in one line, the
    record intact; the scene inside -o is kept too (figures on)."""
    (tmp_path / "s.toml").write_text(SHORT)
    first = run_cli("dynamics", "s.toml", "-o", ".", cwd=tmp_path)
    assert first.returncode == 0, first.stderr
    record = (tmp_path / "trajectory.csv").read_bytes()
    (tmp_path / "rec.toml").write_text(RECORDED)
    proc = run_cli("dynamics", "rec.toml", "-o", ".", cwd=tmp_path)
    assert proc.returncode == 2, proc.stderr
    lines = [x for x in proc.stderr.splitlines() if x.startswith("tengfield")]
    assert len(lines) == 1 and "'trajectory.csv' there is a file this command read" in lines[0]
    assert (tmp_path / "trajectory.csv").read_bytes() == record
    assert (tmp_path / "rec.toml").read_text() == RECORDED
    assert (tmp_path / "s.toml").read_text() == SHORT


def test_another_commands_staging_directory_is_refused_as_output(tmp_path, capsys):
    """#30 item 23: -o DIR/.tengfield-staging-XXXX (its files would vanish with it)."""
    from tengfield import cli

    out = tmp_path / "D"
    staged = StagedOutput(out)
    staging = staged.open()
    try:
        code = cli.main(["map", "--frequency-hz", "10:20:2", "--amplitude-mm", "1",
                         "--no-plots", "-o", str(staging / "sub")])
    finally:
        staged.abort()
    err = capsys.readouterr().err
    assert code == 2
    assert "a tengfield command's staging directory" in err and len(err.splitlines()) == 1
