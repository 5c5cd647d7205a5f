"""``python -m brainpainter`` runs the CLI."""

from brainpainter.cli import main

main()
