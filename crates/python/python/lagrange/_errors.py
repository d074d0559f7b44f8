"""The exceptions of the lagrange package."""


class SceneError(Exception):
    """A scene with mistakes in it: it did not parse, resolve or derive.

    ``str(error)`` names the first mistake as ``file:line:column: message``; the attributes
    say more:

    - ``file``: the file name (``"<string>"`` for :func:`lagrange.loads` unless named), or
      ``"about"`` when the first error is in ``linearize``'s ``about`` argument (its
      ``line`` and ``column`` then count in that text),
    - ``line``, ``column``: 1-based position of the first error,
    - ``rendered``: every diagnostic rendered as the ``lagrange`` command prints it (the
      source line, a caret under the culprit, hints),
    - ``diagnostics``: a list of ``(severity, message, line, column)``.
    """

    def __init__(self, message, *, file=None, line=None, column=None, rendered="", diagnostics=()):
        super().__init__(message)
        self.file = file
        self.line = line
        self.column = column
        self.rendered = rendered
        self.diagnostics = list(diagnostics)


class NumericError(ArithmeticError):
    """The numbers went wrong: a singular mass matrix, a value that became NaN, a run that
    faulted. A faulted :meth:`lagrange.Scene.simulate` attaches what it computed before the
    fault as ``results``."""

    def __init__(self, message, *, results=None):
        super().__init__(message)
        self.results = results
