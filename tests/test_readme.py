"""The README's commands run as written: its first section (which mechanism explains my cells) on small files in a
lab's layout, and no command line in it is a shell pipe or holds a placeholder in brackets."""
from __future__ import annotations

import re
import shlex
from pathlib import Path

import pandas as pd
import pytest

import tenscell as tc
from tenscell.cli import main

README = Path(__file__).resolve().parents[1] / "README.md"


def _blocks() -> list[list[str]]:
    """The command lines of each ```sh block, comments removed."""
    text = README.read_text(encoding="utf-8")
    return [[line.split("  #")[0].strip() for line in block.splitlines() if line.strip()]
            for block in re.findall(r"```sh\n(.*?)```", text, flags=re.S)]


def test_no_command_is_a_shell_pipe_or_a_placeholder():
    for block in _blocks():
        for line in block:
            for cmd in line.split("&&"):
                cmd = cmd.split(">")[0].strip()
                if cmd.startswith("tenscell "):
                    assert "|" not in cmd and "[" not in cmd, cmd  # typed as written, it must run
                    shlex.split(cmd)


def test_the_mechanism_commands_run_as_written(tmp_path, monkeypatch):
    """The first block after `make ...`: study mechanisms, fit --model, moduli --from-fit, on a lab's files."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("TENSCELL_PROGRESS", "0")
    sweep = tc.bundled("fabry2001")  # a lab's export: rad/s and kPa in the headers
    pd.DataFrame({"Angular Frequency [rad/s]": 6.283185307179586 * sweep.frequency_hz,
                  "Storage Modulus [kPa]": sweep.G_storage / 1e3,
                  "Loss Modulus [kPa]": sweep.G_loss / 1e3}).to_csv("my_sweep.csv", index=False)
    tc.bundled("stamenovic2002").to_dataframe().to_csv("my_prestress_sweep.csv", index=False)
    block = next(b for b in _blocks() if b and b[0].startswith("tenscell study mechanisms"))
    assert [c.split()[1] for c in block] == ["study", "fit", "moduli"]
    # the study as written, made small: one mechanism, one start, no ensemble (the full study takes minutes)
    small = ["--mechanisms", "maxwell", "--starts", "1", "--hops", "0", "--ensemble", "0"]
    assert main(shlex.split(block[0])[1:] + small) == 0
    assert (tmp_path / "mechanisms" / "mechanisms.md").is_file()
    assert main(shlex.split(block[1])[1:]) in (0, 1)  # 1: the report says which data set misses the tolerance
    assert "## " in (tmp_path / "fit" / "report.md").read_text()
    assert main(shlex.split(block[2])[1:]) == 0


@pytest.mark.parametrize("name", ["springpot-alpha-family+visc"])
def test_the_readme_names_the_recommended_model(name):
    from tenscell.fitting import RECOMMENDED

    assert name == RECOMMENDED
    assert f"--model {RECOMMENDED}" in README.read_text(encoding="utf-8")
