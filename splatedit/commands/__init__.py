"""The ``splatedit`` sub-commands (``cmd_*(args) -> exit code``), one module
per group; :mod:`splatedit.cli` builds the parser and dispatches to them.
Heavy imports (numpy, scipy, the renderer) happen inside the commands, so
``splatedit -h`` and a mistyped flag stay instant."""
