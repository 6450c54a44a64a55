"""``python -m tgsis.cli``: the ``tgsis`` command."""

import sys

from tgsis.cli import main

sys.exit(main())
