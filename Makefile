# twist-mocap: the two commands a newcomer runs are `make demo` and `make test`.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: venv demo test lint bench bench-quick bench-real bench-walk bench-plates extension clean

venv: $(STAMP)

# Blender 5.0 runs Python 3.11, and its bpy module installs on 3.11 only. A set-up that
# fails leaves no .venv behind, so the next make starts afresh.
$(STAMP): requirements.txt
	@$(PYTHON) -c 'import sys; sys.exit(sys.version_info[:2] != (3, 11))' 2>/dev/null || { \
	  echo "twist-mocap needs Python 3.11 (Blender 5.0's); '$(PYTHON)' is not. Run with one:" \
	       "make PYTHON=python3.11 $(MAKECMDGOALS)" >&2; exit 1; }
	rm -rf $(VENV)
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip || { rm -rf $(VENV); exit 1; }
	$(PY) -m pip install --quiet -r requirements.txt || { rm -rf $(VENV); exit 1; }
	touch $(STAMP)

# Track the bundled example through the add-on: tracked .blend, BVH, FBX, contact sheet.
demo: venv
	$(PY) scripts/demo.py

test: venv
	$(PY) -m pytest

lint: venv
	$(VENV)/bin/ruff check core twist_addon bench tests scripts example_blends

# The benchmark suite: many motions and looks, tracked with the defaults; writes
# docs/BENCHMARK.md. Renders its footage once into .cache/suite/. Add the Bandai Namco
# clips (never stored here) with BENCH_ARGS="--bandai-namco FOLDER".
bench: venv
	$(PY) bench/suite.py --write docs/BENCHMARK.md $(BENCH_ARGS)
	$(BENCH_REAL)

# The real four-camera clip, tracked through its own calibration from three starting frames,
# each camera alone, and each scored point over the first and last frames; writes
# docs/REAL_CLIP.md.
BENCH_REAL = $(PY) bench/real_clip.py --starts 3 --one-view --points --write docs/REAL_CLIP.md \
	--sheet docs/real_clip_sheet.jpg
bench-real: venv
	$(BENCH_REAL)

# The suite's quick check for every change: the CMU clips at 15 fps.
bench-quick: venv
	$(PY) bench/suite.py --quick $(BENCH_ARGS)

# Muybridge's plates tracked from clicked first poses, scored on the animal's outline and on
# points clicked on every frame; writes docs/PLATES.md.
bench-plates: venv
	$(PY) bench/plates.py --write docs/PLATES.md

# The one-clip walk benchmark with its references for one view and one step.
bench-walk: venv
	$(PY) bench/walk_benchmark.py

# The installable extension, one zip per platform, into dist/ (downloads its wheels once).
extension: venv
	$(PY) scripts/build_extension.py

# Everything the build and the runs made: footage, exports, wheels and the environment.
clean:
	rm -rf .cache dist wheels .pytest_cache .ruff_cache $(VENV)
