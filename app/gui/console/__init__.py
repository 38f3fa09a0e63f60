"""The remote operator console (`main.py console opc.tcp://...`): `source.py` is a station over
OPC UA as the views' data source (the in-process runtime's is app/gui/bridge.py), `window.py` the
console's window around the workstation's own views."""
