"""``python -m slslam`` is the ``slslam`` command."""

import sys

try:
    from slslam.cli import entry
except KeyboardInterrupt:  # SIGINT while the modules load: one line, not a traceback
    sys.stderr.write("stopped: interrupted by SIGINT\n")
    sys.exit(130)

entry()
