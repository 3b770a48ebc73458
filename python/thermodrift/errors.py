"""The exceptions and warnings of thermodrift, as the command line's exit statuses map them.

=================  ==================================  ===========
exception          when                                CLI status
=================  ==================================  ===========
``UsageError``     an option or combination is wrong   2
``DataError``      a log or model file is bad          3
``ThermodriftError`` anything else the library refuses 1
``KeyboardInterrupt`` Ctrl-C during a long call        130
=================  ==================================  ===========
"""


class ThermodriftError(Exception):
    """Base of the library's own errors."""


class UsageError(ThermodriftError, ValueError):
    """An option, keyword or combination the command line would refuse (exit status 2)."""


class DataError(ThermodriftError, ValueError):
    """Bad data: ``file``, ``line`` and ``column`` (1-based; 0 when unknown) say where.

    For a DataFrame, ``file`` is ``"DataFrame"``, ``line`` the row's position (1-based)
    and ``column`` the column's position (1-based).
    """

    def __init__(self, message, file="", line=0, column=0):
        super().__init__(message)
        self.file = file
        self.line = line
        self.column = column


class ThermodriftWarning(UserWarning):
    """What the command line prints as ``thermodrift: warning: ...``."""
