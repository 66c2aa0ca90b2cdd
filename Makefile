# One-command set-up on a machine that has only python3.
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
OUT    ?= out

.PHONY: demo test bench install clean

$(VENV)/.installed: pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test]'
	touch $@

install: $(VENV)/.installed

# The main job: plan the office scenario and write its figures to $(OUT)/.
demo: install
	$(VENV)/bin/drake-social show scenarios/office_bar.yaml --out $(OUT)/office_bar

# The whole test suite. pytest exits 5 when it collected no test: that is a failure here.
test: install
	$(PY) -m pytest -q -p no:cacheprovider tests; rc=$$?; \
	if [ $$rc -eq 5 ]; then echo "error: pytest collected no tests"; exit 1; fi; exit $$rc

bench: install
	$(VENV)/bin/drake-social bench --out $(OUT)/bench

clean:
	rm -rf $(VENV) $(OUT) build *.egg-info
