"""``python -m linkwork`` is the ``linkwork`` command line."""

import sys

from .cli import main

sys.exit(main())
