"""``python -m brainpainter`` runs the CLI (signals handled from the first moment: cli/entry.py)."""

from brainpainter.cli.entry import main

main()
