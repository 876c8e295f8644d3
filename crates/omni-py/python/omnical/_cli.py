"""The ``omnical`` console command installed with the wheel (no Rust toolchain needed)."""

from __future__ import annotations

import signal
import sys

from ._omnical import cli_main


def main() -> None:
    """Run the command line; Ctrl-C ends it at once, as it does the native binary."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    sys.exit(cli_main(sys.argv))


if __name__ == "__main__":
    main()
