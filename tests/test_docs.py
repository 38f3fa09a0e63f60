"""The manual (docs/, mkdocs.yml): its reference pages are what docs/gen_reference.py writes from
the code now, and the site builds with `mkdocs build --strict` (a broken link, a missing page or
anchor fails).

The build is a test rather than a second step of `make test` so that it runs on the other core
beside the suite (about 2 s of CPU) and in every run of pytest, CI's too.
"""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def _generator():
    spec = importlib.util.spec_from_file_location("gen_reference", REPO / "docs" / "gen_reference.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_reference_pages_are_what_the_code_says(tmp_path: Path) -> None:
    gen = _generator()
    gen.write(tmp_path)
    fresh = {p.name: p.read_text(encoding="utf-8") for p in tmp_path.glob("*.md")}
    committed = {p.name: p.read_text(encoding="utf-8") for p in gen.REFERENCE.glob("*.md")}
    stale = sorted(name for name in fresh.keys() | committed.keys() if fresh.get(name) != committed.get(name))
    assert not stale, (f"docs/reference/ is stale: {', '.join(stale)} differ from what the code says; "
                       f"run `make reference` (python -m docs.gen_reference) and commit the pages")


def test_manual_builds_strict(tmp_path: Path) -> None:
    result = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "-d", str(tmp_path / "site")],
        cwd=REPO, capture_output=True, text=True, timeout=120,
        env={**os.environ, "NO_MKDOCS_2_WARNING": "1"})
    assert result.returncode == 0, f"mkdocs build --strict failed:\n{result.stdout}\n{result.stderr}"
    assert (tmp_path / "site" / "reference" / "station-toml" / "index.html").is_file()
