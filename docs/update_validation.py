"""Write the tables of a ``tenscell study real-cells`` run into docs/validation.md, with the commit and date.

Run by ``make validate`` after the study: ``python docs/update_validation.py OUT/validation_tables.md
docs/validation.md``. Everything between the page's two markers is replaced by the run's own tables (never numbers
typed by hand) under one line naming the commit the run came from (``git describe --always --dirty``), the date
(UTC) and the command; the rest of the page is prose and stays as written.
"""
from __future__ import annotations

import datetime
import subprocess
import sys
from pathlib import Path

BEGIN = "<!-- validation tables: begin (written by docs/update_validation.py from `make validate`) -->"
END = "<!-- validation tables: end -->"


def commit(repo: Path) -> str:
    """The commit of ``repo`` (``--dirty`` when the work tree differs from it), or "unknown" outside git."""
    try:
        return subprocess.run(["git", "describe", "--always", "--dirty", "--abbrev=12"], cwd=repo, check=True,
                              capture_output=True, text=True).stdout.strip() or "unknown"
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def splice(page: str, tables: str, stamp: str) -> str:
    """``page`` with the text between :data:`BEGIN` and :data:`END` replaced by ``stamp`` and ``tables``."""
    if page.count(BEGIN) != 1 or page.count(END) != 1 or page.index(BEGIN) > page.index(END):
        raise ValueError(f"the page needs one {BEGIN!r} line followed by one {END!r} line")
    head, rest = page.split(BEGIN)
    _, tail = rest.split(END)
    return f"{head}{BEGIN}\n\n{stamp}\n\n{tables.strip()}\n\n{END}{tail}"


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
    page_path.write_text(splice(page_path.read_text(encoding="utf-8"), tables_path.read_text(encoding="utf-8"),
                                stamp), encoding="utf-8")
    print(f"update_validation: wrote the tables of {tables_path} into {page_path} ({stamp})")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
