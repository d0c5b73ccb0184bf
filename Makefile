# tenscell: the two commands a newcomer needs are `make reproduce` and `make test`.
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: reproduce test bench install clean docs typecheck lint validate release-check

$(STAMP): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test]'
	touch $(STAMP)

install: $(STAMP)

reproduce: $(STAMP)
	$(VENV)/bin/tenscell reproduce --out out/

test: $(STAMP)
	$(PY) -m pytest

# the mechanisms against measured cells (docs/validation.md): runs `tenscell study real-cells` when the measured-cell
# data sit beside the repository (they are not shipped), writes its tables and figures to build/validation/ and the
# tables into docs/validation.md with the commit and date; skipped, saying why, where the data are absent
REAL_CELLS ?= ../shared/data/real-cells
validate: $(STAMP)
	@if [ -d "$(REAL_CELLS)" ]; then \
		$(VENV)/bin/tenscell study real-cells --populations --data "$(REAL_CELLS)" --out build/validation && \
		$(PY) docs/update_validation.py build/validation/validation_tables.md docs/validation.md; \
	else \
		echo "make validate: skipped: $(REAL_CELLS) does not exist (the measured-cell data are not shipped with tenscell; give REAL_CELLS=DIR)"; \
	fi

bench: $(STAMP)
	@for b in bench/bench_*.py; do echo "== $$b"; $(PY) $$b || exit 1; done

# the documentation site: API reference, guides, the executed tutorial and the example gallery;
# any warning fails the build. Output in docs/_build/html.
DOCS_STAMP := $(VENV)/.docs-installed
$(DOCS_STAMP): $(STAMP)
	$(PY) -m pip install --quiet -e '.[docs]'
	touch $(DOCS_STAMP)

# then every internal link and #anchor of the built pages must resolve (offline: external links are not fetched)
docs: $(DOCS_STAMP)
	TENSCELL_PROGRESS=0 $(VENV)/bin/sphinx-build -W --keep-going -b html docs docs/_build/html
	$(PY) docs/check_links.py docs/_build/html

# static types (mypy, configured in pyproject.toml)
DEV_STAMP := $(VENV)/.dev-installed
$(DEV_STAMP): $(STAMP)
	$(PY) -m pip install --quiet -e '.[dev]'
	touch $(DEV_STAMP)

typecheck: $(DEV_STAMP)
	$(VENV)/bin/mypy

# the linter (ruff, rules and the reasons for what they leave out in pyproject.toml)
lint: $(DEV_STAMP)
	$(VENV)/bin/ruff check .

# before a release: the sdist and wheel built (dist/), twine's check, what the sdist must hold, and the wheel installed
# in a fresh virtual environment (`tenscell --version`, every public name of 0.2.0 imported); .ci/release-check says how
release-check: $(DEV_STAMP)
	PYTHON=$(PY) .ci/release-check

clean:
	rm -rf $(VENV) out build dist src/*.egg-info .pytest_cache docs/_build docs/api/generated docs/auto_examples docs/jupyter_execute
