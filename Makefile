# cuneate: `make demo` sets up and runs the default job; `make test` sets up and runs the suite.
VENV    ?= .venv
STAMP   := $(VENV)/.cuneate-setup-stamp
PYTEST_ARGS ?=
JOBS    ?= 2

.PHONY: setup demo test bench synth clean

setup: $(STAMP)

$(STAMP): pyproject.toml scripts/setup.sh
	bash scripts/setup.sh
	touch $(STAMP)

demo: setup
	$(VENV)/bin/cuneate demo --out out/demo

test: setup
	mkdir -p build
	$(VENV)/bin/python -m pytest -n $(JOBS) --junitxml=build/junit.xml $(PYTEST_ARGS)
	$(VENV)/bin/python scripts/check_simulators_ran.py build/junit.xml

bench: setup
	CUNEATE_EXTRAS=test,synth bash scripts/setup.sh
	$(VENV)/bin/python -m pytest -m benchmark -s -p no:randomly benchmarks

clean:
	rm -rf build out
