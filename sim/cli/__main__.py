"""``python -m cuneate.sim.cli``: the ``cuneate`` command."""

import sys

from . import main

sys.exit(main())
