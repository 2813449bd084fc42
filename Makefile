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

# Lint, then every test in one pytest invocation (what CI runs).
test: lint
	@$(ENV) && python -m pytest $(PYTEST_ARGS)

# The quick tier for the inner loop: pure cores and unit tests (no DDS, no browser, no Ray, no
# whole session); conftest.py marks them `quick`. `make test` still runs them too.
test-quick: setup
	@$(ENV) && python -m pytest -m quick -q $(PYTEST_ARGS)

clean:
	rm -rf build install log
