# Two commands set everything up on a fresh machine with only python3:
#   make demo   -- create .venv, install the package, segment the built-in demo mesh
#   make test   -- create .venv, install the package and the test tools, run the tests
PYTHON ?= python3
VENV := .venv
# pip shows its progress (what it downloads, the kernels' build) on a terminal
PIP := $(VENV)/bin/python -m pip
KERNELS := CMakeLists.txt $(wildcard src/superfacets/_kernels/cxx/*)
DEMO_STAMP := $(VENV)/.demo-installed
STAMP := $(VENV)/.installed

.PHONY: demo test lint docs bench scale clients pictures sweep comparisons wheel check-wheel \
	install-bench clean

# The environment, with the build's own requirements (pyproject.toml [build-system];
# CMake and Ninja from PyPI where the machine has none): the installs below build in
# it, without pip's isolated build environment, so that build/ stays valid and a later
# install compiles only the kernels' sources that changed.
$(VENV)/bin/python:
	$(PYTHON) -m venv $(VENV)
	$(PIP) install --upgrade pip "scikit-build-core>=0.10" "nanobind>=2.4" \
	    $$(command -v cmake >/dev/null || echo "cmake>=3.18") $$(command -v ninja >/dev/null || echo ninja)

PIP_INSTALL := $(PIP) install --no-build-isolation

# The package with the picture extra (the demo writes a PNG). The compiled kernels are
# built into build/ (about 20 s on 2 cores).
$(DEMO_STAMP): pyproject.toml $(KERNELS) | $(VENV)/bin/python
	$(PIP_INSTALL) -e ".[render]"
	touch $(DEMO_STAMP)

# Everything the tests need (every extra, pytest, ruff, numba for the reference kernels)
$(STAMP): pyproject.toml $(KERNELS) | $(VENV)/bin/python
	$(PIP_INSTALL) -e ".[test]"
	touch $(STAMP)

demo: $(DEMO_STAMP)
	$(VENV)/bin/superfacets demo --output-dir demo-output

# (the tests shared among one worker process per core, at most 4: pytest-xdist)
test: $(STAMP) clients lint
	$(VENV)/bin/python -m pytest -q -n auto --maxprocesses=4

# ruff (pyproject.toml [tool.ruff]): the sources, tests, benchmarks and tools
lint: $(STAMP)
	$(VENV)/bin/ruff check src tests benchmarks tools docs/examples docs/conf.py docs/_cli.py

# The documentation site (Sphinx: user guide, API reference, gallery executed at build
# time) into docs/_build/html, warnings as errors (about 2 minutes). The kernels are not
# built again: build/ already holds them for these sources.
DOCS_STAMP := $(VENV)/.docs-installed
$(DOCS_STAMP): $(STAMP)
	$(PIP_INSTALL) --quiet -e ".[test,docs]"
	touch $(DOCS_STAMP)

docs: $(DOCS_STAMP)
	$(VENV)/bin/python -m sphinx -W --keep-going -b html -q docs docs/_build/html
	$(VENV)/bin/python tools/check_site.py docs/_build/html

# The real clients the tests check their files with, Debian's packages: the HTML page in
# headless Chromium, the PLY's label scalar field in CloudCompare's command line, the PCD's
# label field in PCL's converter. Installed here when missing and possible (root with
# apt-get); otherwise those tests are skipped.
CLIENTS := chromium:chromium CloudCompare:cloudcompare \
	pcl_convert_pcd_ascii_binary:pcl-tools
clients:
	@for pair in $(CLIENTS); do cmd=$${pair%%:*}; pkg=$${pair#*:}; \
	  command -v $$cmd >/dev/null 2>&1 && continue; \
	  if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
	    echo "installing $$pkg (Debian package) for the tests that open files with it..."; \
	    (apt-get install -y -q --no-install-recommends $$pkg >/dev/null 2>&1 || \
	     (apt-get update -q >/dev/null 2>&1 && \
	      apt-get install -y -q --no-install-recommends $$pkg >/dev/null 2>&1)) || \
	    echo "note: could not install $$pkg; the tests that need it will be skipped"; \
	  else echo "note: $$cmd not found; the tests that need it will be skipped"; fi; done

# A wheel of this checkout for this machine's Python and platform, into dist/
# (cibuildwheel, with pyproject.toml's [tool.cibuildwheel], builds them for the others)
wheel: | $(VENV)/bin/python
	$(PIP) wheel --no-deps -w dist .

# That wheel installed with no extras into a fresh environment with no compiler on the
# PATH: the demo and the core commands work, the others name the extra to install;
# prints the install's time and the environment's size (about 1 minute)
check-wheel: wheel
	tools/check_wheel.sh dist

# The install's time and size, and every option's first run against its second
install-bench: $(STAMP)
	$(VENV)/bin/python benchmarks/install.py

# Table 1 meshes, then the scale table up to 1.7M faces (about 2 minutes)
bench: $(STAMP)
	$(VENV)/bin/python benchmarks/table1.py
	$(VENV)/bin/python benchmarks/scale.py

# The scale table up to 27M faces (makes the inputs once, ~1 GB in ~/.cache; ~15 minutes)
scale: $(STAMP)
	$(VENV)/bin/python benchmarks/scale.py --max-faces 3e7

# The pictures in the README (docs/images), made by the command line.
PSB_DIR ?= $(HOME)/.cache/superfacets/psb
pictures: $(STAMP)
	$(VENV)/bin/superfacets panel ../shared/data/meshes/horse.tri.xz --up z --alpha 0 200 1000 \
	    -k 150 --size 640x520 -o docs/images/fig2_horse.png
	$(VENV)/bin/python -c "from superfacets.evaluation.datasets.psb import psb_root; psb_root()"
	for id in 21 101 121 181 281 321; do \
	  $(VENV)/bin/superfacets render $(PSB_DIR)/off/$$id.off -k 150 --size 480x400 \
	      --title "PSB $$id" -o docs/images/psb_$$id.png; done

# The evaluation sweep of the README: about 15 minutes on 2 cores. Its rows and figures
# go to docs/results (not kept in the repository); the figure the guide shows is copied
# to docs/figures.
sweep: $(STAMP)
	$(VENV)/bin/superfacets experiment -o docs/results/psb_sweep.csv
	$(VENV)/bin/superfacets report docs/results/psb_sweep.csv -o docs/results
	cp docs/results/fig4.png docs/results/per_category_*.png docs/figures/

# The paper's comparisons with its baselines (docs/results, README "Comparisons"):
# normalized cuts on a stratified subset (the 2 meshes with fewest faces of each of the
# 15 categories, ~60 min on 2 cores), Shlafman's weighting (~20 min) and VSA (~40 min)
# on all 300 meshes. Each experiment resumes where it stopped when run again.
NCUTS_IDS := 1,9,33,37,52,58,73,74,92,98,111,114,124,125,142,143,185,200,203,214,236,237,257,260,293,298,324,337,367,372
SF := $(VENV)/bin/superfacets
comparisons: $(STAMP)
	$(SF) experiment -o docs/results/ncuts_subset.csv -m superfacets -m ncuts --alpha 0 100 200 \
	    --ids $(NCUTS_IDS)
	$(SF) experiment -o docs/results/shlafman.csv -m shlafman
	$(SF) experiment -o docs/results/vsa.csv -m vsa
	$(SF) report docs/results/ncuts_subset.csv -o docs/results/fig4_fig5_ncuts
	$(SF) report docs/results/psb_sweep.csv docs/results/shlafman.csv -o docs/results/fig6_shlafman \
	    --series "superfacets α=0" --series "superfacets α=100" --series "superfacets α=200" \
	    --series "superfacets α=1000" --series "shlafman α=0.25" --series "shlafman α=0.5" \
	    --series "shlafman α=0.75" --series "shlafman α=1"
	$(SF) report docs/results/psb_sweep.csv docs/results/vsa.csv -o docs/results/fig7_vsa \
	    --series "superfacets α=200" --series "vsa init=random metric=l21" \
	    --series "vsa init=random metric=l2" --series "vsa init=incremental metric=l21" \
	    --series "vsa init=incremental metric=l2"
	for f in fig4_fig5_ncuts/fig4 fig4_fig5_ncuts/cost fig6_shlafman/fig4 fig7_vsa/fig4 \
	    fig7_vsa/per_category_undersegmentation_error; do \
	  name=$$(echo $$f | sed -e 's|^fig4_fig5_||' -e 's|^fig[67]_||' -e 's|/|_|'); \
	  cp docs/results/$$f.png docs/figures/$$name.png; done
	$(SF) panel $(PSB_DIR)/off/1.off --up z $(FIG8) -o docs/images/fig8_vsa_human.png
	$(SF) panel $(PSB_DIR)/off/321.off $(FIG8) -o docs/images/fig8_vsa_mech.png

# The paper's Fig. 8: superfacets against the four VSA variants, k = 150.
FIG8 = -m superfacets vsa -k 150 --param vsa.metric=l21,l2 --param vsa.init=random,incremental \
	--size 300x340 --columns 5 --titles "superfacets, alpha 200" "VSA L2,1 random" \
	"VSA L2 random" "VSA L2,1 incremental" "VSA L2 incremental"

clean:
	rm -rf $(VENV) demo-output build dist src/*.egg-info docs/_build docs/auto_examples
