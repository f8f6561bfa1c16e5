"""Run directories: resolved config, per-generation CSV, champion JSON, atomic checkpoints.

Layout: config.yaml, neat.ini (the INI actually used), generations.csv, champion.json,
segments.json (the arch, device and precision of each start and resume: evolve/records/segments.py),
checkpoints/gen-XXXXX.json.gz (state at the start of generation XXXXX: gzipped JSON, never a
pickle; evolve/runs/checkpoint.py says what it holds). Every file that a crash could
leave half-written is written to a temporary file, flushed to disk and renamed over the old one, so
a kill or a full disk leaves the previous version whole; generations.csv gets one line per
generation appended and flushed to disk instead (rewriting it made every generation cost time in
proportion to the run's length), and a last line cut short by a kill or a full disk, which lacks
its newline, is no row: readers skip it and the next write or a resume drops it. The two newest
checkpoints are kept: a damaged newest one (a disk that lied about fsync, a copy cut short) falls
back to the one before. Nothing else in checkpoints/ is ever loaded: a pickle (an older sgr's
gen-XXXXX.pkl, or one planted under any name) is named in one warning line and skipped, and a run
holding only old pickles is refused with the command that converts them.
Files get the permissions the user's umask gives, as `open()` would create them.
"""

from __future__ import annotations

import csv
import fcntl
import gzip
import io
import json
import os
import re
import stat
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import yaml

from evolve.config import RunConfig
from evolve.records.files import atomic_write, read_yaml, record_json
from tsim.errors import SgrError, printable
from tsim.files import (
    CHECKPOINT_CAP,
    CONFIG_CAP,
    RECORD_CAP,
    make_folder,
    open_no_follow,
    read_gzip,
    read_head,
    read_text,
    refuse_links,
)

COLUMNS = ["generation", "best", "mean", "median", "n_species", "n_valid", "n_invalid", "episodes",
           "build_s", "sim_s", "neat_s", "total_s", "body_diversity"]  # last: added later (NeatSearch)
# a map-elites run's (evolve/methods/map_elites.py): its rows have the archive's coverage and QD score
QD_COLUMNS = [*COLUMNS, "coverage", "qd_score"]
KEEP_CHECKPOINTS = 2
ELITES_FILE = "elites.json"
# an archive kept compact in a results folder (gzip of elites.json; read, never written, by sgr)
ELITES_GZ = "elites.json.gz"
CHECKPOINT = re.compile(r"gen-(\d{5,})\.json\.gz")  # what sgr writes and loads
CHECKPOINT_FORMAT = "sgr-checkpoint"
CHECKPOINT_VERSION = 1
# gzipped, and again uncompressed (1 GiB): the largest seen (1,000 generations, nothing forgotten) ~53 MB
MAX_CHECKPOINT_BYTES = CHECKPOINT_CAP
ENDING = ".writing-end-files"  # present while a run's end files are being written
PICKLE_PROTOCOL_2_PLUS = b"\x80"  # the first byte of every pickle since protocol 2


def checkpoint_generation(path: Path) -> int | None:
    """The generation of an sgr checkpoint file's name (gen-00042.json.gz: 42; five digits or more,
    so generations past 99,999 too); None for any other name (an older sgr's gen-00042.pkl, say).
    The one place checkpoint names are parsed."""
    m = CHECKPOINT.fullmatch(Path(path).name)
    return int(m.group(1)) if m else None


def generation_rows(path: Path) -> tuple[list[dict], list[int]]:
    """generations.csv's rows (dicts of strings), whole lines only (a last line cut short is no row),
    and each row's line number in the file (the header is line 1; blank lines are skipped)."""
    text = read_text(path, RECORD_CAP)
    reader = csv.DictReader(io.StringIO(text[:text.rfind("\n") + 1]))
    rows, lines = [], []
    for row in reader:
        rows.append(row)
        lines.append(reader.line_num)
    return rows, lines


def check_generation_numbers(rows: list[dict], lines: list[int], path: Path) -> int:
    """The first row's generation; SgrError naming the file and the line unless the rows are one
    per generation, in order (sgr writes no other: anything else is a damaged file). A run grown
    from another's checkpoint starts where that stopped; an older sgr's rows count from 0."""
    cells = [str(r.get("generation")) for r in rows]
    for cell, line in zip(cells, lines, strict=True):
        if not re.fullmatch(r"[0-9]{1,12}", cell):
            raise SgrError(f"{path}: line {line} has no generation number (got {cell[:40]!r}): a damaged "
                           "file")
    start = int(cells[0]) if cells else 1
    for i, (cell, line) in enumerate(zip(cells, lines, strict=True)):
        if int(cell) != start + i:
            raise SgrError(f"{path}: line {line} is generation {cell}, not {start + i}: a damaged file")
    return start


def check_fitness(fitness: object, f: Path) -> None:
    """SgrError naming champion record `f` unless `fitness` is a number a float holds (the one rule
    of `champion_of` and `read_champion`: `sgr report` and `load_champion` judge a file alike)."""
    if (isinstance(fitness, bool) or not isinstance(fitness, int | float)
            or isinstance(fitness, int) and abs(fitness) > 1e308):  # float() would overflow
        raise SgrError(f"{f}: key 'fitness' must be a number, got {str(fitness)[:40]!r}")


def champion_of(run_dir: str | Path) -> dict | None:
    """A run's champion.json as read, None where the run has none yet; SgrError naming the file where
    it is not a champion's record (a fitness that is not a number, a body that is not one), so that a
    damaged file is not shown as a run without a champion. A record without a body (a hand-made one)
    is read."""
    from tsim.body import check_robot

    f = Path(run_dir) / "champion.json"
    if not f.exists() and not f.is_symlink():
        return None
    champ = RunDir(run_dir).champion()
    check_fitness(champ.get("fitness"), f)
    try:
        if "body" in champ:
            check_robot(champ["body"])
    except (ValueError, TypeError) as exc:
        raise SgrError(f"{f}: key 'body': {str(exc)[:200]}") from None
    return champ


def _columns(rows: list[dict]) -> list[str]:
    """generations.csv's columns for `rows`: QD_COLUMNS when they are a map-elites run's."""
    return QD_COLUMNS if any("coverage" in r for r in rows) else COLUMNS


def _ends_a_line(path: Path) -> bool:
    """Whether a file exists, is not empty and its last byte is a newline."""
    try:
        with path.open("rb") as f:
            f.seek(0, os.SEEK_END)
            if f.tell() == 0:
                return False
            f.seek(-1, os.SEEK_END)
            return f.read(1) == b"\n"
    except OSError:
        return False


def checkpoint_bytes(data: dict) -> bytes:
    """A checkpoint file's bytes: `data` as JSON (NaN allowed, as Python's json writes it),
    gzipped with no timestamp, so the same state gives the same bytes."""
    text = json.dumps({"format": CHECKPOINT_FORMAT, "version": CHECKPOINT_VERSION, **data},
                      separators=(",", ":"))
    return gzip.compress(text.encode(), compresslevel=3, mtime=0)


def read_checkpoint_file(path: Path) -> dict:
    """A checkpoint file's JSON data, its format and version checked; never unpickles (ValueError
    or gzip/JSON errors for anything else). Read as a file of a folder sgr did not make
    (tsim/files.py `read_gzip`): a regular file, not a link, at most MAX_CHECKPOINT_BYTES gzipped
    and again uncompressed (a small file that would fill the memory is refused)."""
    text = read_gzip(path, MAX_CHECKPOINT_BYTES)  # gzip, one member, as checkpoint_bytes writes
    data = json.loads(text)
    if not isinstance(data, dict) or data.get("format") != CHECKPOINT_FORMAT:
        raise SgrError("not an sgr checkpoint")
    if data.get("version") != CHECKPOINT_VERSION:
        raise SgrError(f"checkpoint version {data.get('version')!r}, this sgr reads {CHECKPOINT_VERSION}")
    if not isinstance(data.get("generation"), int) or isinstance(data["generation"], bool):
        raise SgrError("no generation")
    return data


def is_pickle(path: Path) -> bool:
    """Whether a file looks like a pickle (by its name or first byte; nothing is loaded)."""
    if path.suffix in (".pkl", ".pickle"):
        return True
    try:  # a FIFO, a device or a link is not read (the first would block)
        return read_head(path, 1) == PICKLE_PROTOCOL_2_PLUS
    except (OSError, ValueError):
        return False


def _regular(path: Path) -> bool:
    """Whether `path` is a regular file itself (not a link, a FIFO, a device)."""
    try:
        return stat.S_ISREG(path.lstat().st_mode)
    except OSError:
        return False


def _not_ours(path: Path) -> str:
    """Why a file in checkpoints/ that is not named as sgr's checkpoints is skipped, in a few words;
    only a regular file's first byte is read (a FIFO would block)."""
    try:
        mode = path.lstat().st_mode
    except OSError:
        return "not a checkpoint"
    if stat.S_ISLNK(mode):
        return "a symbolic link, never followed"
    if not stat.S_ISREG(mode) and not stat.S_ISDIR(mode):
        return "not a regular file, never read"
    return "a pickle, never loaded" if is_pickle(path) else "not a checkpoint"


class PickledCheckpoints(SgrError):
    """A run whose only checkpoints are an older sgr's pickles: not loaded without trust."""


class RunDir:
    """One run's directory: its config, generations.csv, champion.json and checkpoints.

    Only the process holding `lock` may write it. It holds config.yaml, neat.ini (the INI actually
    used), generations.csv, champion.json, segments.json and checkpoints/gen-XXXXX.json.gz; the
    module docstring of evolve/records/rundir.py says what each is and how it is written.
    """
    def __init__(self, path: str | Path):
        self.path = Path(path)
        self.ckpt_dir = self.path / "checkpoints"

    def __repr__(self) -> str:
        return f"RunDir({str(self.path)!r})"

    # ------------------------------------------------------------------ one process at a time
    def lock(self) -> None:
        """Hold the run for this process, until it exits or calls `unlock`.

        Two processes advancing one run (a sweep resumed while a run of it still goes on, say) would
        interleave its files.

        Raises:
            ValueError: Another process holds the run (the message gives its pid), the path is not
                a folder, or the run's files hold a symbolic link (`refuse_links`).
        """
        try:
            self.path.mkdir(parents=True, exist_ok=True)
        except (FileExistsError, NotADirectoryError):
            raise SgrError(f"{self.path} is not a folder (a file of that name, or a file on its path): "
                           "a run needs a folder") from None
        fd = open_no_follow(self.path / ".lock", os.O_RDWR | os.O_CREAT)  # a planted link: one line
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.pread(fd, 32, 0).decode(errors="replace").strip() or "?"
            os.close(fd)
            raise SgrError(f"{self.path} is being run by another process (pid {holder})") from None
        try:
            self.refuse_links()
        except SgrError:
            os.close(fd)
            raise
        os.ftruncate(fd, 0)
        os.pwrite(fd, str(os.getpid()).encode(), 0)
        self._lock_fd = fd

    def refuse_links(self) -> None:
        """Refuse a run whose files or checkpoints/ hold a symbolic link.

        The run folder itself may be one: the user named it. A run writes only into its own folder,
        and a planted link (a .lock or generations.csv linked to a file elsewhere, checkpoints/
        linked to another folder) would make it write there instead.

        Raises:
            SgrError: Naming the first symbolic link found.
        """
        for folder in (self.path, self.ckpt_dir):
            if folder is not self.path and not folder.is_dir():
                continue
            refuse_links(folder, self.path)
            with os.scandir(folder) as entries:
                for entry in sorted(entries, key=lambda e: e.name):
                    if entry.is_symlink():
                        refuse_links(Path(entry.path), self.path)

    def unlock(self) -> None:
        """Release the lock taken by `lock`; nothing happens when it is not held."""
        fd = getattr(self, "_lock_fd", None)
        if fd is not None:
            os.close(fd)  # releases the flock
            self._lock_fd = None

    @contextmanager
    def locked_unless_it_fails(self) -> Iterator[RunDir]:
        """`lock`, and `unlock` again if the block raises.

        A run that cannot be started, resumed or opened lets go of its directory; otherwise the lock
        stays held (until `unlock`).
        """
        self.lock()
        try:
            yield self
        except BaseException:
            self.unlock()
            raise

    # ------------------------------------------------------------------ creation
    def create(self, cfg: RunConfig, neat_ini: str | None, extra_files: dict[str, str] | None = None) -> None:
        """Write a new run's config.yaml, neat.ini, any extra files and an empty generations.csv.

        Args:
            cfg: The run's config.
            neat_ini: neat.ini's text; None: no neat.ini (a method without NEAT).
            extra_files: More files to write, name -> text.

        Raises:
            ValueError: The directory already holds a run.
        """
        if (self.path / "generations.csv").exists():
            raise SgrError(f"run directory {self.path} already holds a run; use --resume {self.path} "
                           "or another --out")
        make_folder(self.ckpt_dir, self.path)
        # the arch is not the config's: segments.json records where each part of the run ran
        config = yaml.safe_dump({k: v for k, v in cfg.to_yaml().items() if k != "arch"}, sort_keys=False)
        atomic_write(self.path / "config.yaml", config.encode(), inside=self.path)
        if neat_ini is not None:
            atomic_write(self.path / "neat.ini", neat_ini.encode(), inside=self.path)
        for name, text in (extra_files or {}).items():
            atomic_write(self.path / name, text.encode(), inside=self.path)
        self._write_rows([])

    def config(self) -> dict:
        """config.yaml as written (resolved); ValueError when missing, not YAML or not a run config."""
        f = self.path / "config.yaml"
        if not f.exists() and not f.is_symlink():
            raise SgrError(f"{self.path} is not a run directory (no config.yaml)")
        raw = read_yaml(f, follow=False)  # a FIFO, a device or a link: refused in one line
        if not isinstance(raw, dict) or "method" not in raw:
            raise SgrError(f"{f}: not a run config (no 'method' key)")
        return raw

    def neat_ini(self) -> Path:
        """The path of the run's neat.ini, for neat-python to read (it opens the file itself).

        Raises:
            SgrError: Naming it, unless it is a regular file (neat-python calls a FIFO "no such
                config file"), not a link (one outside the run would be read as the run's own), of
                at most CONFIG_CAP bytes.
        """
        f = self.path / "neat.ini"
        if not os.path.lexists(f):  # neat-python says so, as ever
            return f
        read_head(f, 0)
        if f.stat().st_size > CONFIG_CAP:
            raise SgrError(f"{printable(f)}: over {CONFIG_CAP >> 20} MiB, more than sgr reads in such a file")
        return f

    def save_task(self, reference: dict) -> None:
        """Keep the reference to a task registered in a script (no `imports:` names it).

        So the run renders, reports and resumes in another process that registers it.

        Args:
            reference: The task's name, source file and that file's sha256, as JSON data
                (`task_reference`, tasks/registry.py).
        """
        from tasks.registry import TASK_FILE

        atomic_write(self.path / TASK_FILE, (json.dumps(reference, indent=1) + "\n").encode(),
                     inside=self.path)

    def load_task(self, raw: dict, method: bool = False) -> None:
        """Register the run's own task in this process, unless it is sgr's or registered already.

        It imports the modules its config names (`imports:`), else the file its task reference
        names (a script's); either only after --trust-imports (tasks/registry.py). Reading the
        folder runs nothing.

        Args:
            raw: The run's config.yaml, as read.
            method: The run's method is not registered here, so the modules its config names are
                imported (under the same rule) whatever its task.

        Raises:
            SgrError: In one line, saying how to allow it, when the task may not be loaded or is
                still unknown.
        """
        from tasks.registry import OLD_TASK_FILE, TASK_FILE, import_tasks, load_task_reference
        from tasks.specs import TASKS, unknown_task

        named_in = self.path / "config.yaml"
        if method:
            refs = raw.get("imports")
            for ref in refs if isinstance(refs, list) else ():
                if isinstance(ref, str):
                    import_tasks(ref, named_in=named_in)
            return
        task = raw.get("task")
        if not isinstance(task, str) or task in TASKS:
            return
        refs = raw.get("imports") or ()
        for ref in refs:
            import_tasks(ref, named_in=named_in)
        if not refs and (self.path / TASK_FILE).is_file():
            load_task_reference(self.path / TASK_FILE)
        elif not refs and (self.path / OLD_TASK_FILE).is_file():
            raise SgrError(f"{self.path / OLD_TASK_FILE}: an older sgr kept the run's task {task!r} as a "
                           "pickle, which sgr does not load (it can run any code); register the task in "
                           "your process first, or, if you trust this folder, convert it with: "
                           f"sgr migrate {self.path} --trust-pickle")
        if task not in TASKS:
            raise SgrError(f"{self.path}: {unknown_task(task)}; a task of your own is known once the "
                           f"file that registers it is imported: add imports: [that file] to {named_in}")

    def update_config(self, raw: dict) -> None:
        """Replace config.yaml atomically with `raw` (a resume that extends `generations` does)."""
        atomic_write(self.path / "config.yaml", yaml.safe_dump(dict(raw), sort_keys=False).encode(),
                     inside=self.path)

    # ------------------------------------------------------------------ generations.csv
    def rows(self) -> list[dict]:
        """generations.csv as dicts of strings, [] without the file.

        Whole lines only: a last line cut short is skipped.
        """
        f = self.path / "generations.csv"
        if not os.path.lexists(f):  # (a FIFO or a link is there: refused by the reader, in one line)
            return []
        return generation_rows(f)[0]

    def check_rows(self) -> list[dict]:
        """`rows`, read once and checked: what a resume keeps and appends to.

        Raises:
            SgrError: Naming the file and the line, unless generations.csv holds one row per
                generation, in order.
        """
        f = self.path / "generations.csv"
        if not os.path.lexists(f):  # (a FIFO or a link is there: refused by the reader, in one line)
            return []
        rows, lines = generation_rows(f)
        check_generation_numbers(rows, lines, f)
        return rows

    def _write_rows(self, rows: list[dict]) -> None:
        columns = _columns(rows)
        buf = io.StringIO()
        w = csv.DictWriter(buf, fieldnames=columns, lineterminator="\n")
        w.writeheader()
        for r in rows:
            w.writerow({k: r.get(k, "") for k in columns})  # a column a run's older rows lack: empty
        atomic_write(self.path / "generations.csv", buf.getvalue().encode(), inside=self.path)
        self._header = ",".join(columns)

    def _header_is_ours(self, path: Path, columns: list[str] = COLUMNS) -> bool:
        """Whether generations.csv's header is `columns` (read once per RunDir): a run made before a
        column was added has its file rewritten with the new header by the next append."""
        if getattr(self, "_header", None) is None:
            with path.open() as f:
                self._header = f.readline().rstrip("\n")
        return self._header == ",".join(columns)

    def append_row(self, row: dict) -> None:
        """Append one generation's row to generations.csv, flushed to disk (fsync).

        A last line cut short is dropped by rewriting the file.

        Args:
            row: The row, keys COLUMNS; floats are written with repr, so they read back exactly.
        """
        row = {k: (repr(float(v)) if isinstance(v, float) else v) for k, v in row.items()}
        path = self.path / "generations.csv"
        columns = _columns([row])
        if not _ends_a_line(path) or not self._header_is_ours(path, columns):  # no file, a line cut short,
            # or an older header: rewrite it whole
            self._write_rows([*self.rows(), row])
            return
        buf = io.StringIO()
        csv.DictWriter(buf, fieldnames=columns, lineterminator="\n").writerow({k: row.get(k, "") for k in
                                                                                columns})
        try:
            with os.fdopen(open_no_follow(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, self.path),
                           "ab") as f:
                f.write(buf.getvalue().encode())
                f.flush()
                os.fsync(f.fileno())
        except OSError as exc:
            if exc.filename is None:  # name the file (a full disk)
                raise OSError(exc.errno, exc.strerror, str(path)) from exc
            raise

    def truncate_rows(self, generation: int) -> None:
        """Keep the rows of the first `generation` generations; the others are recomputed after a resume.

        Rows count generations from 1; a run written when they counted from 0 is renumbered.
        """
        rows = self.check_rows()
        if rows and rows[0]["generation"] == "0":  # counted from 0 before: renumber, once
            rows = [{**r, "generation": str(int(r["generation"]) + 1)} for r in rows]
        self._write_rows([r for r in rows if int(r["generation"]) <= generation])

    # ------------------------------------------------------------------ end files
    def begin_end_files(self) -> None:
        """Mark that the end files (fitness.png, champion.gif) are being written.

        Until `end_files_written`, a finished run is not done, and `sgr evolve --resume` writes them
        again (after a full disk or a kill while writing them).
        """
        atomic_write(self.path / ENDING, b"", inside=self.path)

    def end_files_written(self) -> None:
        """The end files are all written whole."""
        (self.path / ENDING).unlink(missing_ok=True)

    def end_files_pending(self) -> bool:
        """Whether writing the end files began and did not end."""
        return (self.path / ENDING).exists()

    # ------------------------------------------------------------------ champion, checkpoints
    def write_champion(self, champion: dict) -> None:
        """Replace champion.json atomically (laid out by `record_json`)."""
        atomic_write(self.path / "champion.json", record_json(champion).encode(), inside=self.path)

    def write_elites(self, elites: dict) -> None:
        """Replace elites.json (a map-elites run's archive, evolve/records/elites.py) atomically."""
        atomic_write(self.path / ELITES_FILE, record_json(elites).encode(), inside=self.path)

    def champion(self) -> dict:
        """champion.json as a dict.

        Raises:
            SgrError: Naming the file, when there is none yet or it is not a JSON object (a damaged
                file: ours are written whole).
        """
        f = self.path / "champion.json"
        if f.exists() and not f.is_file():  # a FIFO or a device would be read forever
            raise SgrError(f"{f}: not a regular file")
        if not f.is_file():
            raise SgrError(f"{self.path} has no champion.json yet")
        try:
            champ = json.loads(read_text(f, RECORD_CAP))
        except (json.JSONDecodeError, UnicodeDecodeError) as exc:
            raise SgrError(f"{f}: not valid JSON ({str(exc)[:200]})") from None
        except RecursionError:
            raise SgrError(f"{f}: not a champion's record (nested too deeply)") from None
        if not isinstance(champ, dict):
            raise SgrError(f"{f}: a champion record is a JSON object, got {type(champ).__name__}")
        return champ

    def save_checkpoint(self, generation: int, data: dict) -> Path:
        """Write `data` atomically as checkpoints/gen-<generation>.json.gz and delete older ones.

        The newest KEEP_CHECKPOINTS checkpoints up to this one are kept. Retention goes by the
        generation just written, not by the names in the folder: a file named after a later
        generation (planted, or left by a damaged run) is never deleted and never makes a real
        checkpoint go, nor is any file that is not a regular one (a FIFO, a link).

        Args:
            generation: Generations done: the checkpoint's number.
            data: JSON-able data: numbers, strings, lists, dicts.

        Returns:
            The checkpoint's path.
        """
        make_folder(self.ckpt_dir, self.path)
        path = self.ckpt_dir / f"gen-{generation:05d}.json.gz"
        atomic_write(path, checkpoint_bytes({"generation": generation, **data}), inside=self.path)
        upto = [f for f in self.checkpoints() if checkpoint_generation(f) <= generation and _regular(f)]
        for old in upto[KEEP_CHECKPOINTS:]:
            old.unlink()
        return path

    def checkpoints(self) -> list[Path]:
        """sgr's checkpoint files (gen-XXXXX.json.gz), newest first."""
        if not self.ckpt_dir.is_dir():
            return []
        found = [(g, f) for f in self.ckpt_dir.iterdir() if (g := checkpoint_generation(f)) is not None]
        return [f for _, f in sorted(found, reverse=True)]

    def last_checkpoint_generation(self, done: int | None = None) -> int | None:
        """Generations done at the newest checkpoint file, None without one.

        Only a regular file, of a generation the run has done, counts.

        Args:
            done: The generations the run has done; None: `generations_done`, read from its files.
                A run under way passes its search's generation, so the loop reads no file back.
        """
        done = self.generations_done() if done is None else done
        for f in self.checkpoints():
            g = checkpoint_generation(f)
            if (done is None or g <= done) and _regular(f):
                return g
        return None

    def generations_done(self) -> int | None:
        """How many generations the run's own records say it has done: the most a checkpoint can be after.

        That is generations.csv's last whole row (an older sgr's rows count from 0), else, without
        rows, config.yaml's `generations`; None when neither can be read.
        """
        f = self.path / "generations.csv"
        try:
            rows, lines = generation_rows(f) if f.exists() or f.is_symlink() else ([], [])
            if rows:
                start = check_generation_numbers(rows, lines, f)
                return start + len(rows) - (start != 0)
        except (OSError, ValueError):  # a damaged file (refused on resume): the config says
            pass
        try:
            g = self.config().get("generations")
        except (OSError, ValueError):
            return None
        return g if isinstance(g, int) and not isinstance(g, bool) else None

    def has_checkpoint(self) -> bool:
        """Whether the run has any checkpoint to resume from, an older sgr's pickled ones included.

        Pickled ones are refused on resume, with the way to convert them, but the run is not lost.
        """
        return bool(self.checkpoints() or self.pickled_checkpoints())

    def pickled_checkpoints(self) -> list[Path]:
        """An older sgr's checkpoints (gen-*.pkl), oldest first; never loaded here."""
        return sorted(self.ckpt_dir.glob("gen-*.pkl")) if self.ckpt_dir.is_dir() else []

    def latest_checkpoint(self, decode: Callable[[dict], dict] | None = None) -> dict | None:
        """The newest checkpoint that loads and that `decode` accepts, None when there is none at all.

        Damaged checkpoints and every other file in checkpoints/ (pickles above all) are skipped,
        named in one warning line.

        Args:
            decode: Checks a checkpoint's data and builds objects; None: the JSON data as it is.

        Returns:
            The checkpoint, as `decode` returns it; None without any checkpoint.

        Raises:
            PickledCheckpoints: There are only an older sgr's pickles.
            ValueError: No checkpoint loads; the message names the files.
        """
        ours = self.checkpoints()
        others = sorted(f for f in self.ckpt_dir.iterdir() if f not in ours and not f.name.startswith(".")
                        ) if self.ckpt_dir.is_dir() else []  # (".": atomic_write's temporary files)
        skipped = [f"{printable(f.name)} ({_not_ours(f)})" for f in others]
        done = self.generations_done()
        if not ours and self.pickled_checkpoints():
            raise PickledCheckpoints(
                f"{self.ckpt_dir} holds only pickled checkpoints of an older sgr "
                f"({', '.join(f.name for f in self.pickled_checkpoints())}); sgr does not load "
                "pickles, which can run any code; if you trust this folder, convert them with: "
                f"sgr migrate {self.path} --trust-pickle")
        damaged = []
        for f in ours:
            if done is not None and checkpoint_generation(f) > done:  # not one this run wrote
                damaged.append(f"{printable(f.name)} (damaged, after generation {checkpoint_generation(f)}, "
                               f"past the {done} this run has done: never read)")
                continue
            try:
                data = read_checkpoint_file(f)
                state = decode(data) if decode is not None else data
            except Exception as exc:  # any damage: truncated, garbage, a planted file, bad fields
                why = str(exc).removeprefix(f"{printable(f)}: ")  # (the reader's errors name the file)
                why = f": {' '.join(why.split())[:120]}" if isinstance(exc, ValueError) else ""
                damaged.append(f"{printable(f.name)} (damaged, {type(exc).__name__}{why})")
                continue
            if damaged or skipped:
                print(f"sgr: warning: skipped {', '.join(damaged + skipped)} in {printable(self.ckpt_dir)}; "
                      f"resuming from {printable(f.name)}", file=sys.stderr)
            return state
        if ours:
            raise SgrError(f"no usable checkpoint in {self.ckpt_dir}: "
                           f"{', '.join(damaged + skipped)}")
        return None
