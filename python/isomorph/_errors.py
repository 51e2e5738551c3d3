"""The exceptions of isomorph (raised by the native module with the Rust message)."""


class MorphError(Exception):
    """A morph, an export or a comparison failed; the message is the Rust error's."""


class InputError(MorphError, ValueError):
    """An input cannot be read or used (unknown name, unreadable file, bad arrays,
    an input the method does not take, shapes that do not overlap, ...)."""


class SettingError(MorphError, ValueError):
    """A keyword setting is unknown, belongs to another method, or has a bad value;
    the message names the setting."""


class Cancelled(MorphError):
    """The operation was cancelled by its ``timeout`` (Ctrl-C raises ``KeyboardInterrupt``)."""
