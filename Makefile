# MonoSkel developer entry point.  A fresh machine needs only python3.11 and make:
#   make demo   - set up Blender 5.0.1 (PyPI bpy) and run the headless batch on the built-in walk
#   make test   - set up Blender 5.0.1, 4.5 LTS and 4.2 LTS, lint, the whole suite under 5.0.1 and the
#                 Blender tests under each LTS
# Other targets: package (per-platform extension zips in dist/), lint, venvs, clean, distclean.

SHELL := /bin/bash
.DEFAULT_GOAL := help

VENV_50 := .venvs/bpy-5.0.1
VENV_45 := .venvs/bpy-4.5
VENV_42 := .venvs/bpy-4.2
PY_50 := $(VENV_50)/bin/python
PY_45 := $(VENV_45)/bin/python
PY_42 := $(VENV_42)/bin/python
PYTEST_ARGS ?=

.PHONY: models help venvs venv-5.0.1 venv-4.5 venv-4.2 lint test test-5.0.1 test-4.5 test-4.2 demo package clean distclean

help:
	@echo "make demo      run the headless batch on built-in data -> out/demo.blend, out/demo_result.json"
	@echo "make test      lint, the whole suite under Blender 5.0.1, the Blender tests under 4.5 and 4.2 LTS"
	@echo "make package   per-platform extension zips (with scipy wheels) in dist/"
	@echo "make lint      ruff over the code"
	@echo "make clean     remove build outputs (distclean: also .venvs/ and wheels/)"

venv-5.0.1:
	@tools/setup_venv.sh 5.0.1

venv-4.5:
	@tools/setup_venv.sh 4.5

venv-4.2:
	@tools/setup_venv.sh 4.2

venvs: venv-5.0.1 venv-4.5 venv-4.2

# BlazePose's model files for the pose detector (from the mediapipe wheel on PyPI, hash-pinned)
models: venv-5.0.1
	@$(PY_50) tools/fetch_pose_models.py

lint: venv-5.0.1
	$(VENV_50)/bin/ruff check .

test-5.0.1: venv-5.0.1
	@echo "=== tests under Blender 5.0.1 ==="
	$(PY_50) -m pytest $(PYTEST_ARGS)

# The LTS releases run the Blender tests: tests/core is plain numpy and scipy, pinned alike in every
# environment, so it runs once, under 5.0.1 (PYTEST_ARGS=tests to run everything under an LTS too).
LTS_TESTS ?= tests/blender

test-4.5: venv-4.5
	@echo "=== Blender tests under Blender 4.5 LTS ==="
	$(PY_45) -m pytest $(if $(PYTEST_ARGS),$(PYTEST_ARGS),$(LTS_TESTS))

test-4.2: venv-4.2
	@echo "=== Blender tests under Blender 4.2 LTS ==="
	$(PY_42) -m pytest $(if $(PYTEST_ARGS),$(PYTEST_ARGS),$(LTS_TESTS))

# Serial on purpose: lint first (cheap, fails early), then 5.0.1, 4.5, 4.2; make stops at the first failure.
# 4.5 runs the 4.4+ slotted-action path on the release before 5.0 removed action.fcurves.
test: venvs models
	@$(MAKE) --no-print-directory lint
	@$(MAKE) --no-print-directory test-5.0.1
	@$(MAKE) --no-print-directory test-4.5
	@$(MAKE) --no-print-directory test-4.2

demo: venv-5.0.1
	@mkdir -p out
	$(PY_50) batch.py --builtin walk --output out/demo.blend --result out/demo_result.json
	$(PY_50) tools/check_demo.py out/demo.blend out/demo_result.json

package: venv-5.0.1 models
	$(PY_50) tools/package.py

clean:
	rm -rf out dist build .pytest_cache .ruff_cache .hypothesis
	find . -path ./.venvs -prune -o -name __pycache__ -type d -exec rm -rf {} +

distclean: clean
	rm -rf .venvs wheels
