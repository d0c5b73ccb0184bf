"""Output sets: a run's directory is always the old complete set or the new one."""
import os
import subprocess
import sys

import pytest

from tenscell.io.outputs import MANIFEST, OutputLocationError, OutputSet, check_output_dir


def _names(d):
    return sorted(os.listdir(d))


def test_set_replaces_previous_as_a_whole(tmp_path):
    d = tmp_path / "o"
    with OutputSet(d, command="tenscell fit a.csv") as s:
        (s / "a.txt").write_text("1")
    assert _names(d) == ["a.txt", MANIFEST]
    with OutputSet(d, command="tenscell fit b.csv") as s:
        (s / "b.txt").write_text("2")
    assert _names(d) == ["b.txt", MANIFEST]
    assert _names(tmp_path) == ["o"]  # no staging, no old copy left


def test_interrupt_leaves_previous_set(tmp_path):
    d = tmp_path / "o"
    with OutputSet(d) as s:
        (s / "a.txt").write_text("1")
    with pytest.raises(KeyboardInterrupt), OutputSet(d) as s:
        (s / "b.txt").write_text("2")
        raise KeyboardInterrupt
    assert _names(d) == ["a.txt", MANIFEST]
    assert (d / "a.txt").read_text() == "1"
    assert _names(tmp_path) == ["o"]


def test_killed_run_staging_is_removed_by_next_run(tmp_path):
    d = tmp_path / "o"
    code = ("import os, sys; from tenscell.io.outputs import OutputSet\n"
            f"s = OutputSet({str(d)!r}).__enter__(); (s / 'x').write_text('x'); os._exit(0)")
    subprocess.run([sys.executable, "-c", code], check=True)
    assert any(n.startswith(".o.tenscell-staging-") for n in _names(tmp_path))
    OutputSet(d)  # constructing the next run cleans up after the dead one
    assert _names(tmp_path) == []


def test_location_refused_before_computation(tmp_path):
    (tmp_path / "file").write_text("x")
    with pytest.raises(OutputLocationError, match="--out .*not a directory"):
        check_output_dir(tmp_path / "file")
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "notes.txt").write_text("x")
    with pytest.raises(OutputLocationError, match="--save .*not empty"):
        OutputSet(tmp_path / "mine", flag="--save")
    check_output_dir(tmp_path / "new" / "deeper")  # missing directories are created later


def test_a_set_of_another_command_or_inside_a_set_is_refused(tmp_path):
    d = tmp_path / "o"
    with OutputSet(d, command="tenscell reproduce --out o") as s:
        (s / "a.txt").write_text("1")
    with pytest.raises(OutputLocationError, match="holds the output set of `tenscell reproduce"):
        OutputSet(d, command="tenscell show paper --out o")
    with pytest.raises(OutputLocationError, match="inside the output set"):
        OutputSet(d / "study", command="tenscell study x")
    (tmp_path / "web").mkdir()
    (tmp_path / "web" / MANIFEST).write_text('{"name": "not ours"}')  # someone else's manifest.json
    with pytest.raises(OutputLocationError, match="holds no tenscell"):
        OutputSet(tmp_path / "web")
    assert _names(d) == ["a.txt", MANIFEST]


def test_temp_file_of_a_killed_writer_is_removed_by_the_next_write(tmp_path):
    from tenscell.io.outputs import write_text

    target = tmp_path / "fit.png"
    code = ("import os; from tenscell.io.outputs import atomic_path\n"
            f"cm = atomic_path({str(target)!r}); cm.__enter__(); os._exit(0)")
    subprocess.run([sys.executable, "-c", code], check=True)
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".fit.png")]  # the 0-byte temp file
    write_text(target, "new")
    assert _names(tmp_path) == ["fit.png"]
