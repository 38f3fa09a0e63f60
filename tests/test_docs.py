"""The manual (docs/, mkdocs.yml): its reference pages are what docs/gen_reference.py writes from
the code now, and the site builds with `mkdocs build --strict` (a broken link, a missing page or
anchor fails); the README stays a short page whose links lead into the manual.

The build is a test rather than a second step of `make test` so that it runs on the other core
beside the suite (about 2 s of CPU) and in every run of pytest, CI's too. It builds mkdocs.yml as it
is but for the search plugin (a fifth of the build): the search index checks nothing of the
manual's (no link, page or anchor), and `make docs` still builds it.
"""

from __future__ import annotations

import importlib.util
import json
import os
import re
import subprocess
import sys
from pathlib import Path

from app.station.config import KEYS, Key, read_station

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
    config = tmp_path / "mkdocs.yml"  # mkdocs.yml without its search index (paths from the repository)
    config.write_text(f"INHERIT: {REPO / 'mkdocs.yml'}\ndocs_dir: {REPO / 'docs'}\nplugins: []\n",
                      encoding="utf-8")
    result = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "-f", config, "-d", tmp_path / "site"],
        cwd=REPO, capture_output=True, text=True, timeout=120,
        env={**os.environ, "NO_MKDOCS_2_WARNING": "1"})
    assert result.returncode == 0, f"mkdocs build --strict failed:\n{result.stdout}\n{result.stderr}"
    assert (tmp_path / "site" / "reference" / "station-toml" / "index.html").is_file()


def _toml_value(key: Key) -> str:
    """A value of the key's kind for a station.toml, within its bounds."""
    kind = key.kind[0] if isinstance(key.kind, tuple) else key.kind
    value = key.default if isinstance(key.default, kind) else None
    if kind is bool:
        return "true" if value is None or value else "false"
    if kind in (int, float):
        return repr(key.bounds[0] if key.bounds else value if value is not None else 1)
    if kind is str:
        return json.dumps(value or "x")
    return "[]" if kind is list else "{}"


def test_every_key_of_the_reference_is_one_the_parser_reads(tmp_path: Path) -> None:
    """The other way round from the KeyError a key read but not declared raises: a key declared but
    not read would be listed in the manual and refused as an unknown setting."""
    lines = [f"{k.name} = {_toml_value(k)}" for k in KEYS[""].values() if k.kind not in (dict, list)]
    for table, keys in KEYS.items():
        if table:
            lines.append(f"[[{table}]]" if KEYS[""][table].kind is list else f"[{table}]")
            lines += [f"{k.name} = {_toml_value(k)}" for k in keys.values()]
    (tmp_path / "station.toml").write_text("\n".join(lines) + "\n", encoding="utf-8")
    _, problems = read_station(tmp_path)
    unknown = [p for p in problems if "unknown setting" in p]
    assert not unknown, "declared in KEYS but not read by the parser:\n" + "\n".join(unknown)


def test_the_readme_is_a_short_page_whose_links_lead_into_the_manual() -> None:
    """The README is the way in (what it is, the two commands, where each reader goes, the layout and
    benchmark tables); what a reader needs beyond it is a page of the manual, so it stays short and
    every link of it leads to a file that exists (mkdocs checks the manual's links, not these)."""
    readme = (REPO / "README.md").read_text(encoding="utf-8")
    prose = [line for line in readme.splitlines() if not line.startswith("|")]
    assert len(prose) <= 150, f"README.md has {len(prose)} lines besides its tables: move details to docs/"
    links = re.findall(r"\]\(([^)\s]+)\)", readme)
    targets = {t.split("#")[0] for t in links if not t.startswith(("#", "http"))}
    missing = sorted(t for t in targets if not (REPO / t).exists())
    assert not missing, f"README.md links to what does not exist: {missing}"
    assert "\n## Benchmarks\n" in readme and "--8<-- [start:benchmarks]" in readme, \
        "docs/benchmarks.md includes the README's benchmark table by its snippet markers"
