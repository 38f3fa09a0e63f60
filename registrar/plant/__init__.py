"""The plant archive on PostgreSQL (docs/architecture.md sections 2 and 10): every station's
records in one database, copied from each station's SQLite archive and read like it. The only
importer of the PostgreSQL driver, so nothing else depends on psycopg's API."""
