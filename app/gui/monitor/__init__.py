"""The Program view (online monitor with forcing): `view.py` draws, `listing.py` computes what to
show from a snapshot, `source.py` is the local runtime or a station over Modbus, `window.py` opens
it from the workstation's menu or from `main.py monitor`."""
