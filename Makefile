# The whole set-up is `make run` or `make test`; both create .venv if missing.
PYTHON ?= python3
# pytest-xdist processes for `make test`, each test file in one of them (its module fixtures
# built once); 2 = the cores of the machine CI runs on
TEST_WORKERS ?= 2
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: install run test lint bench figures clean

install: $(STAMP)

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[dev]"
	touch $(STAMP)

run: install
	$(BIN)/cell run tasks/bins.yaml

lint: install
	$(BIN)/ruff check cell tests examples
	$(BIN)/ruff format --check cell tests examples
	$(BIN)/mypy cell

test: lint
	$(BIN)/python -m pytest -q -p no:cacheprovider -n $(TEST_WORKERS) --dist loadfile --no-loadscope-reorder tests

bench: install
	$(BIN)/cell bench

# Every figure and quoted figure in README.md and docs/ (about 2 h 29 min on 2 cores, most of it
# the random-layout benchmark: 32 min for each of its two sets as last timed together (the
# `test` set alone, one layout at a time: 16 min, 2026-12-01), 15 min without the release
# search and the turn, 27 min with --order bins; the speed trade-off 19 min; the diagnosis on
# another implementation's worlds 16 min). The headline (bench_sort.json) is the `test`
# layouts (seeds from 1000), on which no constant is chosen; the `tune` layouts (seeds 0-19,
# where the arm's constants were chosen) beside it (bench_sort_tune.json), with the
# comparisons of options made on them; the speed trade-off is the `test` layouts. The `test`
# layouts run one at a time (--workers 1), each with the machine to itself and its decisions
# planned on both cores, as a cell's computer would: their planning time and real-time rate
# are the cell's (on Ray, two layouts at a time, each would have one core). The JSON beside
# each figure is what tests/test_readme_figures.py checks the README's quotes against.
# Not here: docs/figures/rerun_run.png needs a screen (docs/recordings.md).
FIG := docs/figures
TMP := build/figures
figures: install
	rm -rf $(TMP) && mkdir -p $(TMP)
	$(BIN)/cell calibrate --n 0 --snapshot robots/cell_scene/scene.png --replace
	$(BIN)/cell run tasks/bins.yaml --no-log --json $(FIG)/run.json
	sed 's/robot: panda/robot: ur10/' tasks/bins.yaml > $(TMP)/bins_ur10.yaml
	$(BIN)/cell run $(TMP)/bins_ur10.yaml --no-log --json $(FIG)/run_ur10.json
	$(BIN)/cell run tasks/bins_ur3.yaml --no-log --json $(FIG)/run_ur3.json
	$(BIN)/cell synth -o $(TMP)/throws.csv --seed 0
	$(BIN)/cell identify $(TMP)/throws.csv -o $(TMP)/ee.yaml --plot $(TMP)/identify --json > $(FIG)/identify.json
	cp $(TMP)/identify/reach_overview.png $(FIG)/identify_reach_overview.png
	$(BIN)/python examples/10_identify_far_campaigns.py 300 650 865 --seeds 3 4 5 --unseen-seeds 10 11 12 --json $(FIG)/identify_far.json > /dev/null
	$(BIN)/python examples/08_residual_unseen_objects.py $(TMP)/08
	cp $(TMP)/08/table51.png $(FIG)/table51_synthetic.png
	cp $(TMP)/08/unseen_targets.png $(FIG)/residual_unseen_synthetic.png
	cp $(TMP)/08/unseen.json $(FIG)/residual_unseen_synthetic.json
	$(BIN)/python examples/09_residual_scene.py $(TMP)/09
	cp $(TMP)/09/unseen_targets_scene.png $(FIG)/residual_unseen_scene.png
	cp $(TMP)/09/unseen_scene.json $(FIG)/residual_unseen_scene.json
	$(BIN)/cell study repeatability --plot $(FIG)/repeatability.png --json > $(FIG)/repeatability.json
	$(BIN)/cell calibrate --n 280 --seed 7 -o $(TMP)/scene_ee.yaml --log $(TMP)/scene.csv
	$(BIN)/cell gap $(TMP)/scene.csv --report docs/scene_gap/nominal.html --json docs/scene_gap/nominal.json
	$(BIN)/cell gap $(TMP)/scene.csv --identify --report docs/scene_gap/identified.html --json docs/scene_gap/identified.json
	$(BIN)/cell gap check --json $(FIG)/gap_check.json
	$(BIN)/python -m cell.bench.bench_real_tracks --json $(FIG)/real_tracks.json > /dev/null
	$(BIN)/cell gap check --worlds other --n 240 --workers 2 --json $(FIG)/gap_check_other.json
	$(BIN)/cell gap check --worlds scene --n 80 --workers 2 --json $(FIG)/gap_check_scene.json
	$(BIN)/python examples/probe_unseen_effects.py --json $(FIG)/probe_unseen.json > /dev/null
	$(BIN)/python examples/11_gap_scene_table.py $(FIG)/gap_check_scene.json > $(TMP)/gap_scene_table.md
	$(BIN)/python -m cell.gap.scene_repeats s:bounce-slide s:bounce-slide-mu03 s:bounce-hop s:bounce-hop-mu05 s:bounce-roll s:bounce-roll-one --jitters 0.0001,0.01 --json $(FIG)/gap_scene_repeats.json > /dev/null
	$(BIN)/cell bench --json > $(FIG)/bench.json
	$(BIN)/python -m cell.bench.bench_scene_reach --n 600 --seed 100 --json $(FIG)/scene_reach_breakdown.json
	$(BIN)/cell bench sort --set test --layouts 20 --robots panda,ur5 --workers 1 --floor --json > $(FIG)/bench_sort.json
	$(BIN)/cell bench sort --set tune --layouts 20 --seed 0 --robots panda,ur5 --workers 2 --floor --json > $(FIG)/bench_sort_tune.json
	$(BIN)/cell bench sort --set tune --layouts 20 --seed 0 --robots panda,ur5 --workers 2 --no-cycle-search --no-turn-release --floor --json > $(FIG)/bench_sort_plain.json
	$(BIN)/cell run tasks/bins.yaml --no-log --no-cycle-search --no-turn-release --json $(FIG)/run_plain.json
	$(BIN)/cell bench sort --set tune --layouts 20 --seed 0 --robots panda,ur5 --workers 2 --order bins --floor --json > $(FIG)/bench_sort_bins.json
	$(BIN)/cell run tasks/bins.yaml --no-log --order bins --json $(FIG)/run_bins.json
	$(BIN)/python -m cell.bench.bench_flywheel --json $(FIG)/flywheel.json
	$(BIN)/cell bench tradeoff --set test --layouts 4 --seed 1000 --robots panda,ur5 --scales 0.5,0.75,1.0 --workers 2 --plot $(FIG)/tradeoff.png --json > $(FIG)/tradeoff.json

clean:
	rm -rf $(VENV) build *.egg-info
