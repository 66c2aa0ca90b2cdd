# One-command set-up on a machine that has only python3.
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
OUT    ?= out

.PHONY: demo test test-fast bench install clean chromium mutate docs

$(VENV)/.installed: pyproject.toml constraints.txt
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -c constraints.txt -e '.[test,bench,docs]'
	touch $@

# numba's cache of the compiled kernels, filled with the commands' argument
# types (a minute or more of CPU once; seconds when the cache is current), so
# that the first command loads machine code instead of compiling it. Redone
# when a source changes (a kernel's edit drops its cached code).
$(VENV)/.kernels: $(VENV)/.installed $(shell find drake_social -name '*.py' 2>/dev/null)
	$(PY) -m drake_social.warmup
	touch $@

install: $(VENV)/.installed $(VENV)/.kernels

# The main job: draw the office scenario, plan it with Social Risk-RRT*, execute
# the path in Drake's Simulator and write the figures, the path, the results and
# a browser replay to $(OUT)/office_bar/.
demo: install
	$(VENV)/bin/drake-social show scenarios/office_bar.yaml --out $(OUT)/office_bar
	$(VENV)/bin/drake-social plan scenarios/office_bar.yaml --algorithm social_rrt_star --out $(OUT)/office_bar
	$(VENV)/bin/drake-social simulate scenarios/office_bar.yaml --path $(OUT)/office_bar/path.csv --out $(OUT)/office_bar
	@echo "outputs in $(OUT)/office_bar/: scene.png path.png cost_profile.png convergence.png path.csv result.json" \
	  "replay.html executed.csv tracking.png motion.png sim.json"
	@echo "watch the transport: open $(abspath $(OUT))/office_bar/replay.html in a browser"

# Headless Chromium for the replay tests (tests/sim/browser.py): installed from
# Debian when missing and we are root; if that fails the browser tests skip.
chromium:
	@if [ ! -x /usr/bin/chromium ] && [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null; then \
	  echo "installing chromium for the replay tests"; \
	  { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium; } >/dev/null \
	    || echo "warning: could not install chromium; the browser tests will skip"; \
	fi

# Test markers (registered in pyproject.toml, [tool.pytest.ini_options]):
#   slow        whole plans, simulations, benchmarks, studies, the path-hash table
#               (by hand: a module's pytestmark or a test's decorator)
#   browser     drives headless Chromium (tests/sim/browser.py; given by rule in
#               tests/conftest.py to every test calling browser.require_chromium())
#   subprocess  starts another process, mostly a Python interpreter or drake-social
#               paying pydrake's imports (by rule in tests/conftest.py)
# make test runs them all (3,253 tests; 13 min 22 s on two cores); make test-fast
# leaves the three out (2,820 tests, about 100 s idle) to iterate with. tests/test_docs.py keeps both counts
# within 15 % of what pytest collects. PYTEST_ARGS adds options to both, e.g.
# make test-fast PYTEST_ARGS='-x -k social'. pytest exits 5 when it collected no
# test: that is a failure here too.
PYTEST_ARGS ?=
FAST := not slow and not browser and not subprocess

test: install chromium
	$(PY) -m pytest -q -p no:cacheprovider $(PYTEST_ARGS) tests; rc=$$?; \
	if [ $$rc -eq 5 ]; then echo "error: pytest collected no tests"; exit 1; fi; exit $$rc

test-fast: install
	$(PY) -m pytest -q -p no:cacheprovider -m '$(FAST)' $(PYTEST_ARGS) tests; rc=$$?; \
	if [ $$rc -eq 5 ]; then echo "error: pytest collected no tests"; exit 1; fi; exit $$rc

# The documentation site (mkdocs.yml, docs/): the README, the guides and an API
# reference from the docstrings, built into site/; any warning is an error.
docs: install
	$(PY) -m mkdocs build --strict -d site

bench: install
	$(VENV)/bin/drake-social bench --out $(OUT)/bench

# Mutation testing of the pure core (cost/, planning/, kinematics.py) with
# mutmut 3 ([tool.mutmut] in pyproject.toml): hours on two cores, so not part
# of make test. Works in mutants/; MUTANTS picks a subset, e.g.
# make mutate MUTANTS='drake_social.kinematics*'. Survivors: mutmut results,
# then mutmut show <name>.
MUTANTS ?=
mutate: install
	$(PY) -m pip install --quiet -e '.[test,bench,mutate]'
	$(VENV)/bin/mutmut run $(MUTANTS)
	$(VENV)/bin/mutmut export-cicd-stats && cat mutants/mutmut-cicd-stats.json

clean:
	rm -rf $(VENV) $(OUT) build site *.egg-info
