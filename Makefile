# Two commands on a fresh machine: `make demo` and `make test`.
# Both create .venv and install everything from requirements*.txt first.

PYTHON ?= python3
VENV ?= .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
DEMO_OUT ?= demo_output

.PHONY: demo test bench lint clean venv

venv: $(STAMP)

# pip comes from the interpreter's own pip where it can install into another environment
# (pip >= 22.3): the venv's ensurepip would install and compile one pip only for it to be
# replaced (9 s against 2 s); ensurepip otherwise. Bytecode is compiled once, on every core
# (pip would compile on one), without the libraries' own tests and the installers: where
# PYTHONDONTWRITEBYTECODE is set, a module without it is compiled again at each import,
# in every process.
$(STAMP): requirements.txt requirements-test.txt setup.py setup.cfg package.xml
	$(PYTHON) -m venv --without-pip $(VENV)
	$(PYTHON) -m pip --python $(BIN)/python install --quiet --disable-pip-version-check \
		--no-compile pip==25.3 || { $(BIN)/python -m ensurepip --default-pip > /dev/null && \
		$(BIN)/python -m pip install --quiet --disable-pip-version-check --upgrade pip==25.3; }
	$(BIN)/python -m pip install --quiet --disable-pip-version-check --no-compile -r requirements-test.txt
	$(BIN)/python -m pip install --quiet --disable-pip-version-check --no-deps --no-build-isolation -e .
	$(BIN)/python -m compileall -q -j 0 -x '/tests?/|/site-packages/(pip|setuptools)/' \
		$(VENV)/lib > /dev/null
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/hydro-sdp demo --out $(DEMO_OUT)

# The test workers (one more than there are cores, test/conftest.py) share the cores:
# one BLAS thread each (more would mostly wait, as the console script knows). The
# package's bytecode first, for the same reason as the libraries'.
test: $(STAMP)
	$(BIN)/python -m compileall -q -j 0 hydro_sdp test > /dev/null
	OPENBLAS_NUM_THREADS=1 $(BIN)/python -m pytest

bench: $(STAMP)
	@for script in bench/bench_*.py; do echo "== $$script"; $(BIN)/python $$script || exit 1; done

clean:
	rm -rf $(VENV) build install log $(DEMO_OUT) *.egg-info .pytest_cache .hypothesis
