"""``python3 -m osc_client``: the command line (osc_client.cli)."""
import sys

from .cli import main

sys.exit(main())
