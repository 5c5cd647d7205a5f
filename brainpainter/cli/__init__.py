"""The ``brainpainter`` command: click commands and options, and the guard that turns errors into
one line and an exit code.
"""
