import sys

from netplc.cli import main

sys.exit(main())
