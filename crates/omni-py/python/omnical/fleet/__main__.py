"""``python -m omnical.fleet FLEET_DIR --out OUT ...``: the same as ``omnical fleet ...``."""

import sys

from . import main

if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
