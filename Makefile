# Two entry points (see README): `make optimize` and `make test`.
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
CONFIG ?= configs/g1_arms.yaml

.PHONY: install optimize test smoke bench clean

install: $(STAMP)

$(STAMP): pyproject.toml
	python3 -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[test]"
	touch $(STAMP)

optimize: $(STAMP)
	$(VENV)/bin/excite optimize $(CONFIG) --force

test: $(STAMP)
	$(PY) -m pytest -q -rs

smoke: $(STAMP)
	$(VENV)/bin/excite optimize configs/smoke.yaml --output results/smoke.h5 --force
	$(VENV)/bin/excite export results/smoke.h5 --rate 1000 --force
	$(VENV)/bin/excite verify-gradient configs/smoke.yaml
	$(VENV)/bin/excite identify configs/panda_identify_simulated.yaml --output results/smoke_identify.h5 --force

bench: $(STAMP)
	$(PY) bench/bench_g1_arms.py

clean:
	rm -rf $(VENV) results
