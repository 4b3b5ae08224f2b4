# Convenience targets; README.md gives the two canonical set-up commands.
VENV ?= .venv
PY := $(VENV)/bin/python

.PHONY: venv quickstart test test-all paper-fa-ifa bench

$(VENV)/bin/tcbench:
	python3 -m venv $(VENV) && $(VENV)/bin/pip install -q 'uv>=0.9,<1' && $(VENV)/bin/uv pip install -q --python $(PY) -e '.[test,bench]'

venv: $(VENV)/bin/tcbench

quickstart: venv
	$(VENV)/bin/tcbench quickstart

test: venv
	$(PY) -m pytest -m "not slow" -q -n 2

test-all: venv
	$(PY) -m pytest -q -n 2

paper-fa-ifa: venv
	PATH=$(VENV)/bin:$$PATH bash experiments/paper_fa_ifa/run.sh

bench: venv
	$(PY) benchmarks/fa_vs_niapy.py --seeds 5
