"""The station: its configuration (`config.py`, station.toml), everything read before it starts
(`load.py`, for the start and `check` alike), the runtime that starts and stops the parts
(`runtime.py`) and `check` (`check.py`). Qt-free: `--no-gui` is this package alone."""
