"""Tags, data quality and alarms: the Qt-free layer that gives NetPlc memory names, units and trust.

`tag.py` says how to read a tag from memory and convert it (the manual's hardware/physical
conversion), `table.py` loads `tags.csv`, `quality.py` derives each address's quality from the
program's NREADs, and `alarms.py` is the ISA-18.2 alarm life cycle evaluated once per scan.
"""
