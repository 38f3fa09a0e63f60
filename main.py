"""NetPlc Station: python main.py [STATION] | --no-gui | view | check | simulate (see --help)."""

import sys

from app.cli import main

if __name__ == "__main__":
    sys.exit(main())
