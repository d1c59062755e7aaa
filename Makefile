# Two entry points (see README): `make optimize` and `make test`.
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
CONFIG ?= configs/g1_arms.yaml

.PHONY: install ipopt optimize test end-to-end lint smoke bare view-check docs docs-serve figure-plots guide bench clean

install: $(STAMP)

$(STAMP): pyproject.toml constraints.txt
	python3 -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -c constraints.txt -e ".[test,mujoco,docs,cluster,view]"
	$(MAKE) --no-print-directory ipopt
	@# the gradient's and the capsule distances' numba kernels compiled (and cached) here, checked
	@# against finite differences on the default robot, so the first `make optimize` runs at full speed
	$(VENV)/bin/excite verify-gradient $(CONFIG) --objective log_trace_inverse > /dev/null || \
	  { echo "excite verify-gradient $(CONFIG) failed: run it to see which gradient"; exit 1; }
	touch $(STAMP)

# IPOPT for optimizer.method: ipopt. cyipopt has no Linux wheel on PyPI, so it is built against
# Debian's coinor-libipopt-dev, installed here when missing (as root with apt-get, as on this
# project's machines); elsewhere install IPOPT yourself, or the method says it is missing.
ipopt:
	@pkg-config --exists ipopt 2>/dev/null || { [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null && \
	  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq \
	  coinor-libipopt-dev liblapack-dev libblas-dev pkg-config >/dev/null; } || true
	@if pkg-config --exists ipopt 2>/dev/null; then $(PY) -m pip install --quiet -c constraints.txt -e ".[ipopt]"; \
	  else echo "IPOPT not found: optimizer.method 'ipopt' is unavailable (SLSQP, the default, works)"; fi

optimize: $(STAMP)
	$(VENV)/bin/excite optimize $(CONFIG) --force

test: $(STAMP)
	$(PY) -m pytest -q -rs -n auto -m "not end_to_end" --durations=10

# The slowest checks of a command end to end (pytest -m end_to_end), run by .ci/run beside the smoke run.
end-to-end: $(STAMP)
	$(PY) -m pytest -q -rs -n auto -m end_to_end --durations=5

lint: $(STAMP)
	$(VENV)/bin/ruff check .
	$(VENV)/bin/ruff format --check .

smoke: $(STAMP)
	$(VENV)/bin/excite optimize configs/smoke.yaml --output results/smoke.h5 --force
	$(VENV)/bin/excite export results/smoke.h5 --rate 1000 --force
	$(VENV)/bin/excite rehearse results/smoke.h5 --record results/smoke_rehearsal --force
	$(VENV)/bin/excite identify configs/panda_identify_rehearsal.yaml --output results/smoke_identify_rehearsal.h5 --force
	$(VENV)/bin/excite verify-gradient configs/smoke.yaml
	$(VENV)/bin/excite identify configs/panda_identify_simulated.yaml --output results/smoke_identify.h5 --force \
	  --mjcf-out results/smoke_identify.xml
	$(VENV)/bin/excite init ur_description/urdf/ur3_robot.urdf --output results/smoke_ur3.yaml --force
	$(VENV)/bin/excite check results/smoke_ur3.yaml
	$(VENV)/bin/excite init g1_description/urdf/g1_29dof_rev_1_0.urdf --output results/smoke_g1.yaml --force
	$(VENV)/bin/excite check results/smoke_g1.yaml

# `pip install .` without extras (a user's own environment): the command line optimizes a shipped
# config; the extras (cluster, view, mujoco, ipopt) are only needed by the options that say so
bare:
	rm -rf .venv-bare
	python3 -m venv .venv-bare
	.venv-bare/bin/python -m pip install --quiet --upgrade pip
	.venv-bare/bin/python -m pip install --quiet -c constraints.txt .
	cd /tmp && $(CURDIR)/.venv-bare/bin/excite optimize $(CURDIR)/configs/smoke.yaml --output $(CURDIR)/results/bare.h5 --force
	$(CURDIR)/.venv-bare/bin/excite rehearse $(CURDIR)/results/bare.h5 2>&1 | grep "pip install 'excite\[mujoco\]'"
	rm -rf .venv-bare

# `excite view` opened in headless Chromium: the screenshot must show the robot (bench/view_check.py).
# A browser is ~300 MB and needs root to install, so it is not part of `make test`; Debian's chromium
# is installed here when missing (as root with apt-get, as for IPOPT), else the check says it skipped.
view-check: $(STAMP)
	@command -v chromium >/dev/null || { [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null && \
	  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null; } || true
	$(PY) bench/view_check.py results/smoke.h5

# the documentation site (mkdocs-material) in site/, warnings as errors
docs: $(STAMP)
	$(VENV)/bin/mkdocs build --strict --quiet

# the site served at http://127.0.0.1:8000, with search (which browsers block on pages opened from disk)
docs-serve: $(STAMP)
	$(VENV)/bin/mkdocs serve

# the plots of docs/figures.md, drawn from its tables into docs/images
figure-plots: $(STAMP)
	$(PY) docs/figure_plots.py

# every command of docs/guide.md, in order, in an empty folder
guide: $(STAMP)
	$(PY) docs/run_guide.py

bench: $(STAMP)
	$(PY) bench/bench_g1_arms.py

clean:
	rm -rf $(VENV) .venv-bare results
