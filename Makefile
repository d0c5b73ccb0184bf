# tenscell: the two commands a newcomer needs are `make reproduce` and `make test`.
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: reproduce test bench install clean docs typecheck lint

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

bench: $(STAMP)
	@for b in bench/bench_*.py; do echo "== $$b"; $(PY) $$b || exit 1; done

# the documentation site: API reference, guides, the executed tutorial and the example gallery;
# any warning fails the build. Output in docs/_build/html.
DOCS_STAMP := $(VENV)/.docs-installed
$(DOCS_STAMP): $(STAMP)
	$(PY) -m pip install --quiet -e '.[docs]'
	touch $(DOCS_STAMP)

docs: $(DOCS_STAMP)
	TENSCELL_PROGRESS=0 $(VENV)/bin/sphinx-build -W --keep-going -b html docs docs/_build/html

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

clean:
	rm -rf $(VENV) out build src/*.egg-info .pytest_cache docs/_build docs/api/generated docs/auto_examples docs/jupyter_execute
