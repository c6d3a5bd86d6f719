import sys

from bittc_core.cli import main

sys.exit(main())
