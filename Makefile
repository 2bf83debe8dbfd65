# HEMS digital twin: `make demo` and `make test` set everything up on a fresh machine.
SHELL := /bin/bash
PYTHON ?= python3.11
VENV := .venv
PY := $(VENV)/bin/python
PREFIX := $(abspath $(VENV))
MSGS_BUILD := build/hems_msgs
PYTEST_ARGS ?=
# Passed to every benchmark of `make bench`; --smoke runs each in seconds without its floors.
BENCH_ARGS ?=
# All six fingers, the 16 nodes composed in one process as `hems up` starts them; a process
# per node: DEMO_ARGS=--separate; one finger's four nodes: DEMO_ARGS="--fingers index".
DEMO_ARGS ?=
# Every process started from here keeps DDS discovery on the loopback interface.
export ROS_AUTOMATIC_DISCOVERY_RANGE ?= LOCALHOST

MSG_SOURCES := $(wildcard hems_msgs/msg/*.msg hems_msgs/srv/*.srv) hems_msgs/CMakeLists.txt hems_msgs/package.xml
# The unit's step kernel compiled ahead of time, so that node processes run without numba
# (hems_ros/physics/compiled.py); an extension module of the venv's Python version.
EXT_SUFFIX := $(shell $(PYTHON) -c "import sysconfig; print(sysconfig.get_config_var('EXT_SUFFIX'))" 2>/dev/null)
AOT_KERNEL := hems_ros/physics/_kernel_aot$(EXT_SUFFIX)

.PHONY: setup demo test test-quick test-graph test-faults bench lint typecheck clean check-system

setup: check-system $(VENV)/.stamp-hems_ros $(AOT_KERNEL)

check-system:
	@tools/check_system.sh $(PYTHON)

$(VENV)/.stamp-venv:
	$(PYTHON) -m venv $(VENV)
	@touch $@

$(VENV)/.stamp-requirements: requirements.lock $(VENV)/.stamp-venv
	$(PY) -m pip install --disable-pip-version-check -q -r requirements.lock
	@touch $@

# rosidl needs the venv as ament prefix; see hems_msgs/CMakeLists.txt for the include fix.
$(VENV)/.stamp-hems_msgs: $(MSG_SOURCES) $(VENV)/.stamp-requirements
	@echo "building hems_msgs (rosidl, cmake) into $(PREFIX)"
	@mkdir -p $(MSGS_BUILD)
	AMENT_PREFIX_PATH=$(PREFIX) CMAKE_PREFIX_PATH=$(PREFIX) cmake -S hems_msgs -B $(MSGS_BUILD) \
	  -DCMAKE_INSTALL_PREFIX=$(PREFIX) -DPython3_EXECUTABLE=$(PREFIX)/bin/python \
	  -DBUILD_TESTING=OFF > $(MSGS_BUILD)/configure.log 2>&1 || { tail -30 $(MSGS_BUILD)/configure.log; exit 1; }
	AMENT_PREFIX_PATH=$(PREFIX) cmake --build $(MSGS_BUILD) -j 2 > $(MSGS_BUILD)/build.log 2>&1 || { tail -30 $(MSGS_BUILD)/build.log; exit 1; }
	cmake --install $(MSGS_BUILD) > $(MSGS_BUILD)/install.log 2>&1 || { tail -30 $(MSGS_BUILD)/install.log; exit 1; }
	@touch $@

$(VENV)/.stamp-hems_ros: setup.py setup.cfg package.xml hems_ros/executables.py tools/ament_install.py $(VENV)/.stamp-hems_msgs
	$(PY) -m pip install --disable-pip-version-check -q --no-deps --no-build-isolation -e .
	$(PY) tools/ament_install.py $(PREFIX)
	@touch $@

$(AOT_KERNEL): $(wildcard hems_ros/physics/*.py) $(VENV)/.stamp-hems_ros
	@echo "compiling the physics step kernel ahead of time ($@)"
	$(PY) -m hems_ros.physics.compiled $@

demo: setup
	$(VENV)/bin/hems demo $(DEMO_ARGS)

test: setup
	tools/run_tests_in_two.sh $(PY) tests $(PYTEST_ARGS)

# make test runs both of these too (tests/foundation/test_lint.py)
lint: setup
	$(VENV)/bin/ruff check hems_ros tests benchmarks tools
	$(VENV)/bin/ruff format --check hems_ros tests benchmarks tools

typecheck: setup
	$(PY) -m mypy

test-quick: setup
	tools/run_pytest.sh $(PY) tests -m "not slow" $(PYTEST_ARGS)

test-graph: setup
	tools/run_pytest.sh $(PY) tests -m graph_realtime $(PYTEST_ARGS)

test-faults: setup
	HEMS_RELIABILITY_PAGE=docs/reliability.md tools/run_pytest.sh $(PY) tests/faults -m faults $(PYTEST_ARGS)

# Every benchmark runs even when one before it misses a floor (exit code 1); the names of
# those that exited non-zero come last, and make fails.
bench: setup
	@failed=""; for b in benchmarks/bench_*.py; do echo "== $$b"; $(PY) $$b $(BENCH_ARGS) || failed="$$failed $$b"; done; \
	if [ -n "$$failed" ]; then echo "exited non-zero (a floor missed or a run failed):$$failed"; exit 1; fi

clean:
	rm -rf $(VENV) build *.egg-info $(AOT_KERNEL)
