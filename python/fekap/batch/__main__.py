"""python -m fekap.batch (scripts/fekap-batch): see fekap.batch.cli."""

import sys

from fekap.batch.cli import main

sys.exit(main())
