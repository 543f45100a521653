"""The one exception type the core raises for bad user input.

Operators and command-line front ends catch :class:`InputError` and show its
message as a single line (``self.report`` in Blender, stderr + exit 2 on the
command line).  Anything else escaping the core is a bug, not bad input.
"""


class InputError(ValueError):
    """Bad or unusable input; the message is a complete one-line explanation."""


class MissingSettingError(InputError):
    """The input lacks a value the caller can supply (``setting`` is ``"fps"`` or ``"image_size"``).

    Front ends that have a sensible fallback (Blender's scene frame rate or
    render size) catch this and retry with it; others show the message.
    """

    def __init__(self, message: str, setting: str):
        super().__init__(message)
        self.setting = setting


class Cancelled(Exception):
    """Raised by a long computation when its ``should_cancel`` callback says so.

    Front ends (the modal Blender operator, the command line on Ctrl-C) catch
    it and leave no partial result behind.
    """
