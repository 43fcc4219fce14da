# hybridwsi: two entry points, both set up .venv from scratch when needed.
#   make run   -> reproduce the paper into results/ (QUICK=1: coarse mesh, about a minute)
#   make test  -> the default test suite (slow full-size runs excluded) on TEST_JOBS pytest-xdist
#                 workers, printing the 15 slowest tests (tests/conftest.py: how it is shared)
PY      ?= python3
VENV    := .venv
BIN     := $(VENV)/bin
STAMP   := $(VENV)/.installed
EXTRAS  ?= all
OUT     ?= results
TEST_JOBS ?= 2
export OPENBLAS_NUM_THREADS ?= 1
export MPLBACKEND ?= Agg

.PHONY: run test test-slow bench install clean

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PY) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[$(EXTRAS)]"
	touch $(STAMP)

install: $(STAMP)

run: $(STAMP)
	$(BIN)/hybridwsi reproduce --out $(OUT) $(if $(QUICK),--quick,)

# --dist loadscope: a test module (tests/conftest.py: or the modules of the shared reproduce
# run) is one unit of work, its fixtures built once; --no-loadscope-reorder: heaviest first
# bytecode kept: where PYTHONDONTWRITEBYTECODE is set, every worker and subprocess otherwise
# compiles the package again and pytest rewrites every test module again in each worker
test: export PYTHONDONTWRITEBYTECODE :=
test: $(STAMP)
	$(BIN)/python -m pytest -q -n $(TEST_JOBS) --dist loadscope --no-loadscope-reorder \
	    --durations=15

test-slow: $(STAMP)
	$(BIN)/python -m pytest -q -m slow --durations=15

bench: $(STAMP)
	for f in benchmarks/bench_*.py; do $(BIN)/python $$f || exit 1; done

clean:
	rm -rf $(VENV) build src/*.egg-info .pytest_cache
