"""User-facing error types shared by every rtaccel Python CLI."""


class UserError(Exception):
    """An error caused by the input or the parameters; CLIs print it as one `error: ...` line and exit 2."""

    def __init__(self, message: str):
        # Keep every message on one line: CLIs promise exactly one error line.
        super().__init__(" ".join(str(message).split()))


class SceneError(UserError):
    """A scene file is missing, unsupported, malformed, empty or has non-finite coordinates."""
