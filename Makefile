# The two commands a user needs: `make demo` and `make test`.
# Both set up everything first (system packages, .venv with Python 3.13, the project).
SHELL := /bin/bash
PYTHON313 ?= $(shell command -v python3.13 2>/dev/null || echo /root/.pyenv/versions/3.13.0/bin/python3.13)
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.isu-installed

.PHONY: demo test setup system clean-venv

setup: $(STAMP)

$(STAMP): pyproject.toml scripts/setup_system.sh
	bash scripts/setup_system.sh
	@test -x $(PY) || $(PYTHON313) -m venv $(VENV)
	$(PY) -m pip install --quiet --disable-pip-version-check -e '.[test]'
	$(PY) -m isu_validate.setup_data
	@touch $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/isu-validate demo --out runs/demo

test: $(STAMP)
	$(PY) -m pytest -q -p no:cacheprovider

clean-venv:
	rm -rf $(VENV)
