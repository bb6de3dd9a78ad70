import sys

from subenv.cli import main

sys.exit(main())
