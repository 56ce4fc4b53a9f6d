# liftoff: `make test` and `make run` set everything up on first use (Debian bookworm).
SYSPY   := /usr/bin/python3
VENV    := .venv
PY      := $(VENV)/bin/python
SYSDEPS := python3-dolfinx-real python3-gmsh python3-meshio python3-venv python3-h5py python3-numba \
           libopenblas0-pthread
SUDO    := $(shell [ "$$(id -u)" = 0 ] || echo sudo)
OUT     ?= out/run
STAMP   := $(VENV)/.installed

.PHONY: check-figures setup test run bench clean check-install

setup: $(STAMP)

# 1) Debian packages for the FE stack (system Python 3.11), only if something is missing.
# 2) A venv that sees them (--system-site-packages), pip for the rest, numpy pinned.
$(STAMP): pyproject.toml constraints.txt
	@if ! $(SYSPY) -c "import dolfinx, gmsh, meshio, h5py, numba, venv, ensurepip" >/dev/null 2>&1 \
	    || ! dpkg -s libopenblas0-pthread >/dev/null 2>&1; then \
	  echo "liftoff setup: installing Debian packages: $(SYSDEPS)"; \
	  $(SUDO) apt-get update -qq && \
	  DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq $(SYSDEPS) >/dev/null; \
	fi
	@test -x $(PY) || $(SYSPY) -m venv --system-site-packages $(VENV)
	@echo "liftoff setup: pip install into $(VENV) (numpy pinned to Debian's build)"
	@$(PY) -m pip uninstall -q -y liftoff 2>/dev/null || true   # the distribution's name before 0.2
	@# pyproject's dependencies and extras, less h5py and pyyeti (Debian's h5py; pyyeti would pull pip's)
	@$(PY) -c "import tomllib; p = tomllib.load(open('pyproject.toml', 'rb'))['project']; \
	  reqs = p['dependencies'] + [r for e in ('viz', 'test', 'nastran', 'dask') for r in p['optional-dependencies'][e]]; \
	  print('\n'.join(r for r in reqs if not r.startswith(('h5py', 'pyyeti'))))" > $(VENV)/requirements.txt
	@$(PY) -m pip install -q --disable-pip-version-check -c constraints.txt -r $(VENV)/requirements.txt
	@$(PY) -m pip install -q --disable-pip-version-check --no-deps -e .
	@$(PY) -m pip install -q --disable-pip-version-check -c constraints.txt --no-deps pyyeti
	@$(PY) -c "import numpy, dolfinx, numba, h5py, pyvista, distributed, imageio; assert numpy.__version__.startswith('1.24'), numpy.__version__"
	@# the transient kernel into numba's cache, its three paths on two cores (2026-11-27: 24 s and 46 s; the batch 20 s; 2026-12-08, an AMD EPYC: 25, 53 and 41 s),
	@# so that the first run does not compile it (transient/warm.py)
	@$(PY) -m liftoff.transient.warm reference batch & p=$$!; $(PY) -m liftoff.transient.warm laws || { wait $$p; exit 1; }; wait $$p
	@touch $(STAMP)

# two pytest-xdist workers (this machine's two cores), whole files per worker (their
# module fixtures built once), the longest files first (tests/conftest.py), BLAS on one
# thread in each (2026-11-27: 848 s; 929 s with two threads each, other work running then).
# The default run's recomputation from an empty cache (marker "figures", 523 s of the 1,024 s
# the whole suite took on 2026-11-28) is `make check-figures`, which .ci/run runs after it.
test: $(STAMP)
	OPENBLAS_NUM_THREADS=1 $(PY) -m pytest -q tests -n 2 --dist loadfile --no-loadscope-reorder -m "not figures"

# the checked-in default figures (README, docs/) against the current code's: the whole default
# run, FE and both cases, from an empty stage cache (benchmarks/default_figures.py --check does
# the same outside pytest)
check-figures: $(STAMP)
	$(PY) -m pytest -q tests/workflows/test_default_figures.py -m figures

run: $(STAMP)
	$(VENV)/bin/liftoff run --out $(OUT)

# A plain `pip install .` (and '.[nastran]') in a venv without Debian's FE stack: `liftoff
# transient` on the vehicle_on_pad example and the Nastran import of the test model, from
# a folder outside the repository (.ci/run runs it after the tests).
PLAIN := /tmp/liftoff-plain-install
check-install:
	rm -rf $(PLAIN) && $(SYSPY) -m venv $(PLAIN)/venv
	$(PLAIN)/venv/bin/pip install -q --disable-pip-version-check '.[nastran]'
	cp -r examples/vehicle_on_pad $(PLAIN)/case && cp tests/data/nastran/inboard.* $(PLAIN)/
	cd $(PLAIN)/case && ../venv/bin/liftoff transient scenario.toml --out out --no-progress > transient.txt
	cd $(PLAIN) && venv/bin/python -c "from liftoff.reduction.nastran import from_extseout; \
	  cb = from_extseout('inboard.op4', name='inboard', units='mm-kg-s'); print('nastran import:', cb.n_modes, 'modes')"
	cd $(PLAIN) && venv/bin/liftoff init --example single_stick stick && test -s stick/payload.pch -a -s stick/pad.geo
	@echo "check-install: a plain pip install runs liftoff transient, the Nastran import and liftoff init"

bench: $(STAMP)
	for b in benchmarks/bench_*.py; do $(PY) $$b || exit 1; done

clean:
	rm -rf $(VENV) out .pytest_cache
