"""``python -m dualarm_qp`` runs the command-line interface."""

import sys

from .cli import main

sys.exit(main())
