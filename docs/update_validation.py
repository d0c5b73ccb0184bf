"""Write the tables and figures of a ``tenscell study real-cells`` run into docs/validation.md, with the commit and
date.

Run by ``make validate`` after the study: ``python docs/update_validation.py OUT/validation_tables.md
docs/validation.md``. Everything between the page's two table markers is replaced by the run's own tables (never
numbers typed by hand) under one line naming the commit the run came from (``git describe --always --dirty``), the
date (UTC) and the command. The run's figures (``OUT/validation_*.png``, :data:`FIGURES`) are copied to
``docs/img/validation/`` and everything between the two figure markers is replaced by them, each with its caption
and the same line; a figure the run did not draw (a part it left out) is removed from the page and from the folder.
The rest of the page is prose and stays as written.

The figures are images computed from the measured data (model fits, slopes, bands), committed so that the built
documentation shows them; the data files themselves are never copied into the repository.
"""
from __future__ import annotations

import datetime
import shutil
import subprocess
import sys
from pathlib import Path

BEGIN = "<!-- validation tables: begin (written by docs/update_validation.py from `make validate`) -->"
END = "<!-- validation tables: end -->"
FIGURES_BEGIN = "<!-- validation figures: begin (written by docs/update_validation.py from `make validate`) -->"
FIGURES_END = "<!-- validation figures: end -->"
#: the figures the page shows, in order: file stem (``tenscell.plotting.validation.validation_figures``) -> caption
FIGURES = {
    "validation_heldout": "Every model refitted on 1–30 Hz of each line's median and scored at 100 and 200 Hz (the "
                          "held-out RMS of the log10 errors, decades; a band where the run gives one, over the fits "
                          "the training data cannot tell apart); dashed: G3's limit; shaded: the power law + "
                          "Newtonian.",
    "validation_population": "Each cell's exponent against its stiffness, measured (grey) and in the mechanism's "
                             "population fitted to every cell (colour), each with its least-squares slope.",
    "validation_slopes": "Each cell's G′ slope between 3 and 30 Hz, measured, against that of each model fitted to "
                         "that cell alone; dashed: model = measured.",
}
#: where the figures go, relative to the page
IMAGE_DIR = Path("img") / "validation"


def commit(repo: Path) -> str:
    """The commit of ``repo`` (``--dirty`` when the work tree differs from it), or "unknown" outside git."""
    try:
        return subprocess.run(["git", "describe", "--always", "--dirty", "--abbrev=12"], cwd=repo, check=True,
                              capture_output=True, text=True).stdout.strip() or "unknown"
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def splice(page: str, tables: str, stamp: str, begin: str = BEGIN, end: str = END) -> str:
    """``page`` with the text between ``begin`` and ``end`` (the table markers by default) replaced by ``stamp`` and
    ``tables``."""
    if page.count(begin) != 1 or page.count(end) != 1 or page.index(begin) > page.index(end):
        raise ValueError(f"the page needs one {begin!r} line followed by one {end!r} line")
    head, rest = page.split(begin)
    _, tail = rest.split(end)
    return f"{head}{begin}\n\n{stamp}\n\n{tables.strip()}\n\n{end}{tail}"


def figures_markdown(names: list[str]) -> str:
    """The MyST of the figures ``names`` (stems of :data:`FIGURES`, in its order): each a ``figure`` directive with
    its caption, as wide as the text and linked to the full-size image."""
    return "\n\n".join(f"```{{figure}} {(IMAGE_DIR / f'{n}.png').as_posix()}\n:width: 100%\n:alt: {n}\n\n"
                       f"{FIGURES[n]}\n```" for n in FIGURES if n in names) or "*This run drew no figure.*"


def copy_figures(out: Path, page_dir: Path) -> list[str]:
    """Copy the run's figures (``out/<stem>.png`` for each stem of :data:`FIGURES`) into ``page_dir/img/validation``
    and remove those of earlier runs it did not draw; the stems copied."""
    target = page_dir / IMAGE_DIR
    target.mkdir(parents=True, exist_ok=True)
    copied = []
    for name in FIGURES:
        source, dest = out / f"{name}.png", target / f"{name}.png"
        if source.is_file():
            shutil.copyfile(source, dest)
            copied.append(name)
        elif dest.exists():
            dest.unlink()
    return copied


def main(argv: list[str]) -> int:
    if len(argv) != 2:
        print("usage: python docs/update_validation.py OUT/validation_tables.md docs/validation.md", file=sys.stderr)
        return 2
    tables_path, page_path = Path(argv[0]), Path(argv[1])
    if not tables_path.is_file():
        print(f"update_validation: {tables_path}: no such file (run `tenscell study real-cells` first)",
              file=sys.stderr)
        return 2
    when = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC")
    stamp = (f"*Written by `make validate` from commit `{commit(page_path.resolve().parent)}` on {when} "
             f"(`tenscell study real-cells`, default budgets).*")
    page = splice(page_path.read_text(encoding="utf-8"), tables_path.read_text(encoding="utf-8"), stamp)
    figures = copy_figures(tables_path.parent, page_path.parent)
    page = splice(page, figures_markdown(figures), stamp, FIGURES_BEGIN, FIGURES_END)
    page_path.write_text(page, encoding="utf-8")
    print(f"update_validation: wrote the tables of {tables_path} and {len(figures)} figure(s) into {page_path} "
          f"({stamp})")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
