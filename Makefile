# Two commands set everything up on a fresh machine with only python3:
#   make demo   -- create .venv, install, segment the built-in demo mesh
#   make test   -- create .venv, install, run the test suite
PYTHON ?= python3
VENV := .venv
STAMP := $(VENV)/.installed

.PHONY: demo test bench clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(VENV)/bin/python -m pip install --quiet --upgrade pip
	$(VENV)/bin/python -m pip install --quiet -e ".[test]"
	touch $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/superfacets demo --output-dir demo-output

test: $(STAMP)
	$(VENV)/bin/python -m pytest -q

bench: $(STAMP)
	$(VENV)/bin/python benchmarks/table1.py

clean:
	rm -rf $(VENV) demo-output build src/*.egg-info
