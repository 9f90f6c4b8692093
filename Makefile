# twist-mocap: the two commands a newcomer runs are `make demo` and `make test`.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: venv demo test lint bench extension clean

venv: $(STAMP)

$(STAMP): requirements.txt
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -r requirements.txt
	touch $(STAMP)

# Track the bundled example through the add-on: tracked .blend, BVH, FBX, contact sheet.
demo: venv
	$(PY) scripts/demo.py

test: venv
	$(PY) -m pytest

lint: venv
	$(VENV)/bin/ruff check core twist_addon bench tests scripts example_blends

# The tracking benchmark (renders its footage once into .cache/, ~10 minutes).
bench: venv
	$(PY) bench/walk_benchmark.py

# The installable extension, one zip per platform, into dist/ (downloads its wheels once).
extension: venv
	$(PY) scripts/build_extension.py

clean:
	rm -rf .cache dist .pytest_cache
