"""``python -m nsd_cli`` is the ``nsd`` command."""
import sys

from nsd_cli.main import main

sys.exit(main())
