"""The station: its configuration (`config.py`, station.toml), everything read before it starts
(`load.py`, for the start and `check` alike), the runtime that starts and stops the parts
(`runtime.py`), `check` (`check.py`), the extras a configuration needs (`extras.py`), one station
per folder (`lock.py`), backup and restore (`backup.py`), what it tells systemd as a service
(`service.py` over `notify.py`), and the demo station (`demo/`, package data). Qt-free:
`--no-gui` is this package alone."""
