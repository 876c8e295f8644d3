"""The ``omnical`` console command installed with the wheel (no Rust toolchain needed)."""

from __future__ import annotations

import signal
import sys

from ._omnical import cli_main


def main() -> None:
    """Run the command line; Ctrl-C acts as in the native binary (it ends the command at once, except
    during ``train``, where it stops the search and keeps the best model so far)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    sys.exit(cli_main(sys.argv))


if __name__ == "__main__":
    main()
