"""`python -m app.gui.sounds`: write the shipped alarm sounds again."""

from app.gui.sounds import main

main()
