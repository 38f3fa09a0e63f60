# Quick start: `make run` (demo station) and `make test` (whole suite, headless).
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: run test lint bench screenshots translations dist docs reference durations clean

$(STAMP): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --disable-pip-version-check -q -e '.[test]'
	touch $(STAMP)

# the console's translations: .ts sources in the repository, compiled by PySide6's lrelease
QM := $(patsubst %.ts,%.qm,$(wildcard app/gui/i18n/*.ts))
%.qm: %.ts $(STAMP)
	$(VENV)/bin/pyside6-lrelease -silent $< -qm $@

translations: $(QM)

run: $(STAMP) $(QM)
	$(PY) main.py

# the tests' temporary folders (station folders, archives, PostgreSQL clusters) in RAM where /dev/shm
# can be written: their SQLite commits and fsyncs cost a run 3-5 s of its 100 on this machine. One
# folder per user and checkout, which pytest empties at the start of the next run; kept after a
# failing run for a look, removed after a passing one
TESTTMP := $(shell test -d /dev/shm -a -w /dev/shm && echo /dev/shm/netplc-tests-$$(id -u)-$$(printf %s "$(CURDIR)" | cksum | cut -d' ' -f1))

test: $(STAMP) $(QM)
	QT_QPA_PLATFORM=offscreen $(PY) -m pytest -q -n 5 $(if $(TESTTMP),--basetemp=$(TESTTMP))
	$(if $(TESTTMP),rm -rf $(TESTTMP))
	$(PY) -m ruff check .

lint: $(STAMP)
	$(PY) -m ruff check .

bench: $(STAMP)
	for b in bench/*.py; do QT_QPA_PLATFORM=offscreen $(PY) $$b || exit 1; done

# the wheel (dist/netplc_station-*.whl) with the demo station and the compiled translations inside
dist: $(STAMP) $(QM)
	$(PY) -m pip wheel --no-deps -q -w dist .

# the manual: docs/ built by MkDocs into build/site (make test builds it --strict as well, in
# tests/test_docs.py); `make reference` rewrites docs/reference/ from the code
docs: $(STAMP)
	NO_MKDOCS_2_WARNING=1 $(PY) -m mkdocs build --strict -d build/site

reference: $(STAMP)
	$(PY) -m docs.gen_reference

# the test files' times of the last `make test`, kept for a clean clone's first run (tests/conftest.py)
durations:
	$(PY) -c "import json, pathlib; d = json.loads(pathlib.Path('.pytest_cache/v/netplc/file_durations').read_text()); pathlib.Path('tests/file_durations.json').write_text(json.dumps({k: round(v, 1) for k, v in sorted(d.items()) if pathlib.Path(k).exists()}, indent=0) + chr(10))"

screenshots: $(STAMP) $(QM)
	QT_QPA_PLATFORM=offscreen $(PY) -m app.gui.screenshots docs/screenshots

clean:
	rm -rf $(VENV) build dist *.egg-info
