"""``python -m tcbench`` is the ``tcbench`` command."""

import sys

from tcbench.cli import main

sys.exit(main())
