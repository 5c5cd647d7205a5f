"""``python -m brainpainter`` runs the CLI."""

from brainpainter.cli.main import main

main()
