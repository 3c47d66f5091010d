"""``python -m ftcomp``."""

import sys

from ftcomp.cli import main

sys.exit(main())
