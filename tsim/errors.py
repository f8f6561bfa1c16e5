"""The one class of error that is the user's to fix (a bad config, flag, file or body): the `sgr`
command prints its message as one line and exits 2. Every layer raises it for bad input and may
import it (it imports nothing). Any other exception is a bug of sgr's, or of a user's own code,
and keeps its traceback."""


class SgrError(ValueError):
    """Bad input, the user's to fix, described in one line.

    The message names the key, flag or file and the problem. A ValueError, so code that catches
    ValueError (and evogym-style callers) still does.
    """


_CONTROL = {c: f"\\x{c:02x}" for c in [*range(0x20), *range(0x7f, 0xa0)]}  # C0, DEL and C1


def printable(text: str) -> str:
    """`text` with every control character (C0, DEL, C1) written as `\\xNN`: a file name from a
    stranger's folder, printed raw, could move the cursor, retitle the terminal or hide a line.

    Args:
        text: what is about to be printed (a name, an error line).

    Returns:
        The same text, but for its control characters, each now four printable ones.
    """
    return str(text).translate(_CONTROL)
