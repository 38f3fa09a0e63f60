"""NetPlc Station: the station's packages (station, scada, authority, publish, gui), the command line
and the log. The version is here, read by the package build (pyproject.toml) and `--version`."""

__version__ = "0.4.0.dev0"
