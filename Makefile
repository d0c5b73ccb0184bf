# tenscell: the two commands a newcomer needs are `make reproduce` and `make test`.
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: reproduce test check bench install clean docs typecheck lint validate release-check

$(STAMP): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test]'
	touch $(STAMP)

install: $(STAMP)

reproduce: $(STAMP)
	$(VENV)/bin/tenscell reproduce --out out/

# the whole suite over the machine's CPUs (pytest-xdist), each test file on one worker so that its module fixtures are
# computed once; `$(PY) -m pytest` alone runs it in one process
test: $(STAMP)
	$(PY) -m pytest -n auto --dist loadfile

# does the install work? (about a minute; `make test` is the whole suite): the command line answers, a formula and a
# mechanism fitted to the bundled data, and the tests of the pipeline's core (structure -> equilibrium ->
# linearization -> response), of the data readers and of the output sets
CHECK_TESTS ?= tests/test_core.py tests/test_data.py tests/test_outputs.py tests/test_study_protocol.py
check: $(STAMP)
	@set -e; tmp=$$(mktemp -d); trap 'rm -rf "$$tmp"' EXIT; \
	$(PY) -m tenscell --version; \
	TENSCELL_PROGRESS=0 $(PY) -m tenscell moduli --prestress 1000 --freq 1 > "$$tmp/moduli.csv"; \
	TENSCELL_PROGRESS=0 $(PY) -m tenscell fit bundled:fabry2001 --model structural-damping --out "$$tmp/formula" \
		|| test $$? = 1; \
	TENSCELL_PROGRESS=0 $(PY) -m tenscell fit bundled:stamenovic2002 bundled:fabry2001 \
		--model springpot-tension+visc --out "$$tmp/mechanism" || test $$? = 1; \
	$(PY) -m pytest -q -p no:cacheprovider $(CHECK_TESTS); \
	echo "make check: tenscell works (the whole suite: make test)"

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

# every benchmark; bench/bench_goals.py first: issue 35's goals as ratios and CPU times, each with the load
bench: $(STAMP)
	@for b in bench/bench_goals.py $$(ls bench/bench_*.py | grep -v bench_goals); do echo "== $$b"; $(PY) $$b || exit 1; done

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
