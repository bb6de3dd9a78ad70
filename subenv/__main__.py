"""``python -m subenv``: the ``subenv`` command (:func:`subenv.cli.main`)."""

import sys

from subenv.cli import main

sys.exit(main())
