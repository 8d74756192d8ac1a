# armlab — two commands on a fresh machine: `make run` and `make test` (see README.md).
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: setup run test test-all ci-sweep bench lint clean-venv

$(STAMP): pyproject.toml
	$(PY) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[dev]"
	touch $(STAMP)

setup: $(STAMP)

# install, run the default protocol (conditioning_window) and print its window sweep
run: $(STAMP)
	$(BIN)/armlab run protocol=conditioning_window

# the suite on TEST_WORKERS processes (pytest-xdist; 2 = this project's 2-core CI machine):
# --dist loadfile keeps each test module in one worker, so its shared (module-scoped) fixtures are
# computed once; --no-loadscope-reorder keeps the collection order, whose heaviest modules come
# first (tests/conftest.py HEAVY_FIRST) so that both workers finish together.
# `make test TEST_WORKERS=0` runs it in this one process.
TEST_WORKERS ?= 2
PYTEST := $(BIN)/python -m pytest -q -n $(TEST_WORKERS) --dist loadfile --no-loadscope-reorder

test: $(STAMP)
	$(PYTEST)

# adds the slow tests, among them 3-job multiruns through the Ray and submitit launchers (the
# optional extras armlab[ray] and armlab[slurm], installed here)
$(VENV)/.extras: $(STAMP) pyproject.toml
	$(BIN)/python -m pip install --quiet -e ".[dev,ray,slurm]"
	touch $(VENV)/.extras

test-all: $(VENV)/.extras
	$(PYTEST) -m "slow or not slow"

# the observation-window sweep CI gates on (.ci/window_sweep.py; docs/ci_window_sweep.md), then
# the proof that the gate fails on an estimator broken on purpose
ci-sweep: $(STAMP)
	$(BIN)/python .ci/window_sweep.py
	$(BIN)/python -m pytest -q -m slow tests/test_window_sweep.py

bench: $(STAMP)
	$(BIN)/python benchmarks/bench_protocol.py
	$(BIN)/python benchmarks/bench_fractional.py
	$(BIN)/python benchmarks/bench_realtime.py
	$(BIN)/python benchmarks/bench_stiffness5.py
	$(BIN)/python benchmarks/bench_diagnosis.py
	$(BIN)/python benchmarks/bench_design.py

lint: $(STAMP)
	$(BIN)/ruff check armlab tests benchmarks
	$(BIN)/ruff format --check armlab tests benchmarks

clean-venv:
	rm -rf $(VENV)
