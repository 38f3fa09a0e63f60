"""The form designer (the manual's ФрегатБаза): `python main.py design [FORM.hmi | STATION]`."""
