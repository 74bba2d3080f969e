# Two commands set everything up on a fresh machine with only python3:
#   make demo   -- create .venv, install, segment the built-in demo mesh
#   make test   -- create .venv, install, run the test suite
PYTHON ?= python3
VENV := .venv
STAMP := $(VENV)/.installed

.PHONY: demo test bench browser pictures sweep clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(VENV)/bin/python -m pip install --quiet --upgrade pip
	$(VENV)/bin/python -m pip install --quiet -e ".[test]"
	touch $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/superfacets demo --output-dir demo-output

test: $(STAMP) browser
	$(VENV)/bin/python -m pytest -q

# The HTML page is tested in headless Chromium (Debian's package). Installed here
# when missing and possible (root with apt-get); otherwise that one test is skipped.
browser:
	@command -v chromium >/dev/null 2>&1 || { \
	  if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
	    echo "installing chromium (Debian package) for the browser test..."; \
	    (apt-get install -y -q --no-install-recommends chromium >/dev/null 2>&1 || \
	     (apt-get update -q >/dev/null 2>&1 && \
	      apt-get install -y -q --no-install-recommends chromium >/dev/null 2>&1)) || \
	    echo "note: could not install chromium; the browser test will be skipped"; \
	  else echo "note: chromium not found; the browser test will be skipped"; fi; }

bench: $(STAMP)
	$(VENV)/bin/python benchmarks/table1.py

# The pictures in the README (docs/images), made by the command line.
PSB_DIR ?= $(HOME)/.cache/superfacets/psb
pictures: $(STAMP)
	$(VENV)/bin/superfacets panel ../shared/data/meshes/horse.tri.xz --up z --alpha 0 200 1000 \
	    -k 150 --size 640x520 -o docs/images/fig2_horse.png
	$(VENV)/bin/python -c "from superfacets.datasets.psb import psb_root; psb_root()"
	for id in 21 101 121 181 281 321; do \
	  $(VENV)/bin/superfacets render $(PSB_DIR)/off/$$id.off -k 150 --size 480x400 \
	      --title "PSB $$id" -o docs/images/psb_$$id.png; done

# The evaluation sweep of the README (docs/results): about 15 minutes on 2 cores.
sweep: $(STAMP)
	$(VENV)/bin/superfacets experiment -o docs/results/psb_sweep.csv
	$(VENV)/bin/superfacets report docs/results/psb_sweep.csv -o docs/results

clean:
	rm -rf $(VENV) demo-output build src/*.egg-info
