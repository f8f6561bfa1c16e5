"""The one class of error that is the user's to fix (a bad config, flag, file or body): the `sgr`
command prints its message as one line and exits 2. Every layer raises it for bad input and may
import it (it imports nothing). Any other exception is a bug of sgr's, or of a user's own code,
and keeps its traceback."""


class SgrError(ValueError):
    """Bad input, described in one line that names the key, flag or file and the problem. A
    ValueError, so code that catches ValueError (and evogym-style callers) still does."""
