# cuneate: `make demo` sets up and runs the default job; `make test` sets up and runs the suite.
VENV    ?= .venv
STAMP   := $(VENV)/.cuneate-setup-stamp
PYTEST_ARGS ?=
JOBS    ?= 2

.PHONY: setup demo test test-long test-release crosscheck bench clean

setup: $(STAMP)

$(STAMP): pyproject.toml scripts/setup.sh
	bash scripts/setup.sh
	touch $(STAMP)

demo: setup
	$(VENV)/bin/cuneate run --out out/demo

# The default suite (both HDL simulators must pass cases); long builds and sweeps are left to
# the long lane below, which CI runs after this one.
test: setup
	mkdir -p build
	$(VENV)/bin/python -m pytest -n $(JOBS) -m "not long and not release and not benchmark and not crosscheck" \
	    --durations=30 --junitxml=build/junit.xml $(PYTEST_ARGS)
	$(VENV)/bin/python scripts/check_simulators_ran.py build/junit.xml

# Place and route, long runs and sweeps: real instances of each long kind.
test-long: setup
	mkdir -p build
	$(VENV)/bin/python -m pytest -n $(JOBS) -m "long and not release and not crosscheck" \
	    --durations=30 --junitxml=build/junit-long.xml $(PYTEST_ARGS)

# Outside CI: what only re-measures (multi-seed fmax, the filled-device builds, proofs at sizes
# already proven). Run it when you change those areas; its last result is recorded under
# benchmarks/release.md.
test-release: setup
	mkdir -p build
	$(VENV)/bin/python -m pytest -n $(JOBS) -m "release" -s \
	    --junitxml=build/junit-release.xml $(PYTEST_ARGS)

# Independent simulators in their own environments (snnTorch on a CPU build of PyTorch, made
# by scripts/crosscheck_env.sh in build/crosscheck-venv): the NIR cross-check.
crosscheck: setup
	mkdir -p build
	bash scripts/crosscheck_env.sh >/dev/null
	$(VENV)/bin/python -m pytest -n 1 -m crosscheck --junitxml=build/junit-crosscheck.xml \
	    $(PYTEST_ARGS)

bench: setup
	$(VENV)/bin/python -m pytest -m benchmark -s -p no:randomly benchmarks

clean:
	rm -rf build out
