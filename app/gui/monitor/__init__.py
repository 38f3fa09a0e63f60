"""The Program view (online monitor with forcing): `view.py` draws, `listing.py` computes what to
show from a snapshot, `source.py` is the local runtime, a station over OPC UA (as one of its users)
or over Modbus (read-only), `login.py` logs in to a station over OPC UA, `window.py` opens it from
the workstation's menu or from `main.py monitor`."""
