"""``python -m slslam`` is the ``slslam`` command."""

import sys

from slslam.cli import main

sys.exit(main())
