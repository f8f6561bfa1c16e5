"""What the attack tests share (tests/**/test_untrusted_*.py): a folder is data from a stranger.

Each attack plants something in a run or sweep folder, runs an sgr command on it and then checks the
four promises of docs/RELIABILITY.md ("A folder is data from a stranger"):
- no planted code ran: planted code would create `Attack.marker`, which must not exist;
- nothing outside the folder changed: `Attack.decoy` is a tree of files outside it (a shell
  start-up file among them) that planted links point at; its checksums are compared before and after;
- nothing was deleted: every path the folder held before the command is still there after it;
- the command ended within a time bound, with one line that names the problem (no traceback).
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import signal
import stat
import subprocess
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

# planted Python that leaves the marker when it runs: a module named by `imports:`, a task script
PLANTED_CODE = "open({marker!r}, 'a').close()\n"


def tree(root: Path) -> dict[str, tuple]:
    """Every path under `root` (links not followed): its kind, and for a regular file its size,
    permission bits and sha256; for a link its target."""
    out: dict[str, tuple] = {}
    root = Path(root)
    if not root.exists() and not root.is_symlink():
        return out
    for dirpath, dirnames, filenames in os.walk(root, followlinks=False):
        for name in dirnames + filenames:
            p = Path(dirpath) / name
            st = p.lstat()
            rel = p.relative_to(root).as_posix()
            if stat.S_ISLNK(st.st_mode):
                out[rel] = ("link", os.readlink(p))
            elif stat.S_ISREG(st.st_mode):
                out[rel] = ("file", st.st_size, stat.S_IMODE(st.st_mode),
                            hashlib.sha256(p.read_bytes()).hexdigest())
            elif stat.S_ISDIR(st.st_mode):
                out[rel] = ("dir",)
            else:
                out[rel] = ("other", stat.S_IFMT(st.st_mode))
    return out


@dataclass
class Result:
    """What a command did: its exit code, what it printed and how long it took."""
    code: int
    out: str
    err: str
    seconds: float

    def error_line(self) -> str:
        """The command's one error line; AssertionError unless it exited non-zero with exactly one
        line on stderr, `sgr: error: ...`, and no traceback."""
        lines = [ln for ln in self.err.splitlines() if ln.strip()]
        assert self.code != 0, f"exit 0, expected an error: {self.err}"
        assert "Traceback" not in self.err, self.err
        assert len(lines) == 1, f"expected one line, got {len(lines)}:\n{self.err}"
        assert lines[0].startswith("sgr: error: "), lines[0]
        return lines[0]


class Attack:
    """One attack's scene in `tmp`: a decoy tree outside the folder under attack, and the marker
    planted code would create. `check(folder, before)` asserts the promises after a command."""

    def __init__(self, tmp: Path):
        self.tmp = Path(tmp)
        self.marker = self.tmp / "PLANTED-CODE-RAN"
        self.decoy = self.tmp / "home"
        self.decoy.mkdir(parents=True, exist_ok=True)
        (self.decoy / ".bashrc").write_text("# the user's shell start-up file\nexport PATH=$PATH\n")
        (self.decoy / "thesis.tex").write_text("\\section{Results}\n" * 20)
        (self.decoy / "data").mkdir(exist_ok=True)
        (self.decoy / "data" / "results.csv").write_text("seed,return\n0,1.5\n1,2.5\n")
        self._decoy_before = tree(self.decoy)

    def code(self) -> str:
        """Python source that creates the marker when it runs."""
        return PLANTED_CODE.format(marker=str(self.marker))

    def run(self, *args: str, timeout: float = 60, cwd: Path | None = None,
            env: dict | None = None) -> Result:
        """`sgr ARGS` in a new process; AssertionError (naming the command) when it has not ended
        within `timeout` seconds: a hang, killed with its process group."""
        t0 = time.monotonic()
        proc = subprocess.Popen([sys.executable, "-m", "evolve.cli", *args], cwd=cwd or self.tmp,
                                env={**os.environ, "PYTHONHASHSEED": "0", **(env or {})},
                                stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                text=True, start_new_session=True)
        try:
            out, err = proc.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()
            raise AssertionError(f"sgr {' '.join(args)} did not end within {timeout} s (a hang)") from None
        return Result(proc.returncode, out, err, time.monotonic() - t0)

    def main(self, *args: str, capsys, timeout: float = 30) -> Result:
        """`sgr ARGS` in this process (evolve.cli.main), cut off by SIGALRM after `timeout` seconds
        (a blocking open or read is interrupted, and the test fails as a hang)."""
        from evolve.cli import main

        def hung(signum, frame):
            raise AssertionError(f"sgr {' '.join(args)} did not end within {timeout} s (a hang)")

        old = signal.signal(signal.SIGALRM, hung)
        signal.setitimer(signal.ITIMER_REAL, timeout)
        t0 = time.monotonic()
        capsys.readouterr()
        try:
            code = main(list(args))
        finally:
            signal.setitimer(signal.ITIMER_REAL, 0)
            signal.signal(signal.SIGALRM, old)
        captured = capsys.readouterr()
        return Result(code, captured.out, captured.err, time.monotonic() - t0)

    def check(self, folder: Path | None = None, before: dict | None = None) -> None:
        """The promises: the marker is absent, the decoy tree is unchanged, and every path that
        `folder` held (`before`, from `tree(folder)`) is still there."""
        assert not self.marker.exists(), "planted code ran"
        assert tree(self.decoy) == self._decoy_before, "a file outside the folder changed"
        if folder is not None and before is not None:
            after = tree(folder)
            lost = sorted(set(before) - set(after))
            assert not lost, f"deleted from {folder}: {lost}"

    @contextlib.contextmanager
    def watching(self, folder: Path) -> Iterator[None]:
        """Inside: a command under attack; after it, `check(folder, tree before)`."""
        before = tree(folder)
        yield
        self.check(folder, before)
