"""What names a plant archive: a postgresql:// URL, checked without the driver, so that the
station file's check and the archive's readers tell a URL from a file without loading psycopg.
The password never travels in the URL: libpq reads PGPASSWORD or ~/.pgpass.
"""

from __future__ import annotations

from typing import TypeGuard
from urllib.parse import urlsplit

URL_SCHEMES = ("postgresql://", "postgres://")


def is_url(target: object) -> TypeGuard[str]:
    return isinstance(target, str) and target.startswith(URL_SCHEMES)


def url_problem(url: str) -> str:
    """Why `url` cannot name a plant archive ("" if it can)."""
    try:
        parts = urlsplit(url)
        parts.port  # noqa: B018 (raises ValueError on a bad port)
    except ValueError as e:
        return f"not a valid PostgreSQL URL: {e}"
    if parts.password is not None:
        return ("a password must not be written in station.toml: give it in PGPASSWORD "
                "or ~/.pgpass")
    if not parts.path.strip("/"):
        return "name the database: postgresql://user@host:5432/DATABASE"
    return ""
