"""Exceptions shared by every layer.

Everything the user can cause (bad files, bad edit scripts, bad parameters)
raises a subclass of :class:`SplatEditError`; the CLI turns those into a
one-line message and exit code 2.  Anything else is a bug.
"""

from __future__ import annotations


class SplatEditError(Exception):
    """Base class of all user-facing errors."""


class InputError(SplatEditError):
    """Bad input data, located as precisely as we can.

    The message names the file and, where known, the element (PLY element
    name such as ``vertex``), the row (0-based index into that element) and
    the property (``x``, ``nx``, ...), in the style of plyfile's errors::

        bunny.ply: element 'vertex': row 17: property 'x': value is NaN
    """

    def __init__(self, message: str, *, path: str | None = None,
                 element: str | None = None, row: int | None = None,
                 prop: str | None = None):
        self.path = path
        self.element = element
        self.row = row
        self.prop = prop
        self.reason = message
        parts = []
        if path is not None:
            parts.append(str(path))
        if element is not None:
            parts.append(f"element {element!r}")
        if row is not None:
            parts.append(f"row {row}")
        if prop is not None:
            parts.append(f"property {prop!r}")
        parts.append(message)
        super().__init__(": ".join(parts))


class EditScriptError(SplatEditError):
    """A bad value in a JSON edit script; names the JSON path of the value,
    e.g. ``edit.json: $.edits[0].transform.rotate.axis: must be 3 numbers``."""

    def __init__(self, message: str, *, json_path: str = "$", path: str | None = None):
        self.json_path = json_path
        self.path = path
        self.reason = message
        prefix = f"{path}: " if path else ""
        super().__init__(f"{prefix}{json_path}: {message}")


class ParameterError(SplatEditError):
    """A bad function or command-line parameter; names the parameter."""

    def __init__(self, name: str, message: str):
        self.name = name
        super().__init__(f"parameter {name!r}: {message}")


class SolverError(SplatEditError):
    """The deformation could not be fitted (for example an empty band)."""


class InputWarning(UserWarning):
    """Input that was read, but not all of it (e.g. rows after the counts a
    PLY header declares).  Issued with :func:`warnings.warn`; the CLI prints
    it as one line ``splatedit: warning: ...``.  The message names the file."""
