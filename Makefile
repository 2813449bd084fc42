# The two commands of the README. Each one sets everything up first (idempotent, see
# scripts/setup.sh), so a fresh clone needs nothing installed by hand.
SHELL := /bin/bash
ENV := source scripts/env.sh

.PHONY: setup run test test-quick lint clean

setup:
	@bash scripts/setup.sh

# Main job: see README ("make run").
run: setup
	@$(ENV) && python scripts/main_job.py $(ARGS)

lint: setup
	@$(ENV) && ruff check src test scripts bench conftest.py

# Tests run on TEST_WORKERS pytest-xdist workers, a test module per worker at a time
# (--dist loadscope: a module's shared set-up, such as the nine sessions of
# test_engine_equivalence.py, runs once). Two workers on the 2-core machine took the suite from
# 13 min 10 s to 8 min 43 s (README): many tests wait on DDS, on wall time or on node start-up
# rather than compute. TEST_WORKERS=0 runs them in the one pytest process as before.
TEST_WORKERS ?= 2
PYTEST_WORKERS = $(if $(filter 0,$(TEST_WORKERS)),,-n $(TEST_WORKERS) --dist loadscope)

# Lint, then every test in one pytest invocation (what CI runs).
test: lint
	@$(ENV) && python -m pytest $(PYTEST_WORKERS) $(PYTEST_ARGS)

# The quick tier for the inner loop: pure cores and unit tests (no DDS, no browser, no Ray, no
# whole session); conftest.py marks them `quick`. `make test` still runs them too.
test-quick: setup
	@$(ENV) && python -m pytest -m quick -q $(PYTEST_WORKERS) $(PYTEST_ARGS)

clean:
	rm -rf build install log
