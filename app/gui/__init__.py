"""The operator workstation and the offline viewer (the only Qt code of app/)."""
