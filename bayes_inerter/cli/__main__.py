"""``python -m bayes_inerter.cli``: the command line, as ``bayes-inerter``."""

import sys

from . import main

sys.exit(main())
