"""A run folder is data from a stranger: what sgr reads there never hangs it, never fills the memory,
and never decides which of its files sgr deletes (docs/RELIABILITY.md, issue 57).

Every file sgr reads from a run folder (and `sgr validate` from a data folder) goes through one
reader (tsim/files.py): regular files only (a FIFO, a device or a socket is refused without being
opened for long: O_NONBLOCK), never a link inside the folder (O_NOFOLLOW), and at most a cap, before
and after decompression. Checkpoints are kept by the generations the run wrote, not by the names in
checkpoints/; names are printed with their control characters escaped.

The scene (tests/evolve/attack.py): planted files, links to a decoy tree outside the folder, then an
sgr command in this process cut off by SIGALRM (a hang fails the test), and the promises checked.
"""

from __future__ import annotations

import gzip
import json
import os
import shutil
import zlib
from pathlib import Path

import pytest
import yaml

from evolve.records.rundir import RunDir
from tests.evolve.attack import Attack
from tests.evolve.conftest import TINY
from tsim.errors import SgrError

pytestmark = [pytest.mark.slow]

GENERATIONS = 3  # checkpoints after every generation: gen-00002 and gen-00003 are kept
BOUND = 30  # seconds any one command may take here (the run's generations are tiny)
MiB = 1 << 20


@pytest.fixture(scope="module")
def finished(tmp_path_factory) -> Path:
    """A finished tiny sgr run of 3 generations, a checkpoint after each (the last two kept)."""
    from evolve.runs.experiment import Experiment

    folder = tmp_path_factory.mktemp("tiny") / "run"
    with Experiment.from_config({"method": "sgr", **TINY, "generations": GENERATIONS, "checkpoint_every": 1},
                                folder, quiet=True) as exp:
        exp.run_all()
    assert [f.name for f in RunDir(folder).checkpoints()] == ["gen-00003.json.gz", "gen-00002.json.gz"]
    return folder


@pytest.fixture
def run(finished, tmp_path) -> Path:
    """This test's own copy of the finished run (under a folder of its own, beside the decoy)."""
    return Path(shutil.copytree(finished, tmp_path / "folder" / "run"))


def gzip_bomb(path: Path, inflated: int) -> int:
    """Write a gzip file of `inflated` zero bytes to `path`, compressed as it goes (never more than
    1 MiB in memory); returns its size on disk."""
    squeeze = zlib.compressobj(9, zlib.DEFLATED, 16 + zlib.MAX_WBITS)
    block = bytes(MiB)
    with path.open("wb") as f:
        for _ in range(inflated // MiB):
            f.write(squeeze.compress(block))
        f.write(squeeze.compress(bytes(inflated % MiB)))
        f.write(squeeze.flush())
    return path.stat().st_size


def plant(kind: str, path: Path, attack: Attack, real: Path | None = None) -> None:
    """Put at `path` a file that is not what its name says: a FIFO, a link to /dev/zero, a link to
    a copy of `real` outside the folder (a checkpoint of another run, say), a gzip bomb."""
    if kind == "outside":
        elsewhere = attack.tmp / f"elsewhere-{path.name}"
        shutil.copy(real, elsewhere)
    path.unlink(missing_ok=True)
    if kind == "fifo":
        os.mkfifo(path)
    elif kind == "devzero":
        path.symlink_to("/dev/zero")
    elif kind == "outside":
        path.symlink_to(elsewhere)
    elif kind == "bomb":
        assert gzip_bomb(path, 9 * MiB) < 64 << 10  # a few KiB that inflate to 9 MiB
    else:
        raise AssertionError(kind)


# ------------------------------------------------------------------ checkpoints


@pytest.mark.parametrize("kind", ["fifo", "devzero", "outside", "bomb"])
def test_resume_skips_a_newest_checkpoint_that_is_no_regular_file_or_too_large_and_goes_on_from_the_real_one(
        run, tmp_path, capsys, monkeypatch, kind):
    """A FIFO named as the newest checkpoint blocked `sgr evolve --resume` forever, one linked to
    /dev/zero filled the memory, one linked outside the folder was loaded, a gzip bomb inflated to
    the old 4 GiB cap: a FIFO or a bomb is now skipped as damaged in the one warning line, never
    read (the cap is lowered to 8 MiB here, so the bomb stays small), and the run resumes from the
    real one; a link (to /dev/zero, or outside) in a run about to be written is refused in one
    line before anything is read."""
    import evolve.records.rundir as rundir

    monkeypatch.setattr(rundir, "MAX_CHECKPOINT_BYTES", 8 * MiB)
    attack = Attack(tmp_path)
    newest = run / "checkpoints" / "gen-00003.json.gz"
    plant(kind, newest, attack, real=newest)
    with attack.watching(run):
        r = attack.main("evolve", "--resume", str(run), "--quiet", capsys=capsys, timeout=BOUND)
    if kind in ("devzero", "outside"):  # a link in a run about to be written: refused before any read
        line = r.error_line()
        assert f"{newest}: a symbolic link, which sgr does not follow inside a folder ({run}" in line, line
        return
    assert r.code == 0, r.err
    warning = [ln for ln in r.err.splitlines() if ln.startswith("sgr: warning: skipped")]
    assert len(warning) == 1, r.err
    why = {"fifo": "not a regular file (a FIFO)", "devzero": "a symbolic link, which sgr does not follow",
           "outside": "a symbolic link, which sgr does not follow", "bomb": "over 8 MiB once uncompressed"}
    assert warning[0].startswith("sgr: warning: skipped gen-00003.json.gz (damaged, SgrError: "
                                 f"{why[kind]}"), warning[0]
    assert warning[0].endswith("resuming from gen-00002.json.gz")
    assert len(RunDir(run).rows()) == GENERATIONS  # generation 3 run again, from generation 2's state


def test_the_checkpoint_cap_is_1_gib_and_a_larger_file_is_refused_before_it_is_read(tmp_path):
    """Checkpoints are read up to 1 GiB gzipped and 1 GiB uncompressed (the largest seen is ~53 MB;
    the old 4 GiB let a few checkpoints fill a 24 GiB machine); a file over the cap is refused by
    its size, before a byte is read (a sparse file: no disk is used)."""
    import evolve.records.rundir as rundir
    from tsim.files import CHECKPOINT_CAP

    assert rundir.MAX_CHECKPOINT_BYTES == CHECKPOINT_CAP == 1024 * MiB
    big = tmp_path / "gen-00009.json.gz"
    with big.open("wb") as f:
        f.truncate(CHECKPOINT_CAP + 1)
    with pytest.raises(SgrError, match=rf"^{big}: over 1024 MiB, more than sgr reads"):
        rundir.read_checkpoint_file(big)


def test_a_gzip_bomb_is_refused_at_the_cap_once_uncompressed_without_inflating_past_it(tmp_path):
    """`read_gzip` stops inflating one byte past its cap: a few KiB that would inflate to 64 MiB are
    refused at a 1 MiB cap in one line naming the file; a file of exactly the cap is read."""
    from tsim.files import read_gzip

    bomb = tmp_path / "bomb.gz"
    assert gzip_bomb(bomb, 64 * MiB) < 128 << 10
    with pytest.raises(SgrError, match=rf"^{bomb}: over 1 MiB once uncompressed"):
        read_gzip(bomb, MiB)
    exact = tmp_path / "exact.gz"
    exact.write_bytes(gzip.compress(bytes(MiB)))
    assert read_gzip(exact, MiB) == bytes(MiB)


def test_select_champion_ends_with_fifos_in_checkpoints_and_chooses_from_the_real_newest(run, tmp_path,
                                                                                          capsys):
    """A FIFO named as a later checkpoint (gen-00009) and one under any other name (whose first byte
    `is_pickle` read) blocked `sgr select-champion` forever: now both are named in the warning line
    and never opened for reading, and the champion is chosen from generation 3's checkpoint."""
    attack = Attack(tmp_path)
    os.mkfifo(run / "checkpoints" / "gen-00009.json.gz")
    os.mkfifo(run / "checkpoints" / "notes")
    with attack.watching(run):
        r = attack.main("select-champion", str(run), "--candidates", "1", "--episodes", "1",
                        capsys=capsys, timeout=BOUND)
    assert r.code == 0, r.err
    warning = [ln for ln in r.err.splitlines() if ln.startswith("sgr: warning: skipped")]
    assert len(warning) == 1, r.err
    assert "gen-00009.json.gz (damaged, after generation 9, past the 3 this run has done" in warning[0]
    assert "notes (not a regular file, never read)" in warning[0]
    assert warning[0].endswith("resuming from gen-00003.json.gz")


def test_planted_later_checkpoint_names_evict_no_real_checkpoint_and_are_never_resumed_from(run, tmp_path,
                                                                                            capsys):
    """Retention went by the names in checkpoints/: planted later names (a copy of a real checkpoint
    as gen-00100, garbage as gen-99999) made the run delete the checkpoint it had just written, and
    resume from the planted one. Now, after two more generations, the run's own two newest
    checkpoints are kept, the planted files are left as they were, and a resume skips them."""
    attack = Attack(tmp_path)
    ckpts = run / "checkpoints"
    shutil.copy(ckpts / "gen-00003.json.gz", ckpts / "gen-00100.json.gz")
    (ckpts / "gen-99999.json.gz").write_bytes(b"not a checkpoint")
    planted = {n: (ckpts / n).read_bytes() for n in ("gen-00100.json.gz", "gen-99999.json.gz")}
    r = attack.main("evolve", "--resume", str(run), "--generations", "5", "--quiet", capsys=capsys,
                    timeout=BOUND)
    attack.check()  # (the run's own gen-00002 and gen-00003 go, as retention keeps two)
    assert r.code == 0, r.err
    assert "resuming from gen-00003.json.gz" in r.err
    names = sorted(f.name for f in ckpts.iterdir())
    assert names == ["gen-00004.json.gz", "gen-00005.json.gz", "gen-00100.json.gz", "gen-99999.json.gz"]
    assert {n: (ckpts / n).read_bytes() for n in planted} == planted
    assert RunDir(run).last_checkpoint_generation() == 5
    state = RunDir(run).latest_checkpoint()
    assert state["generation"] == 5
    err = capsys.readouterr().err
    assert "gen-00100.json.gz (damaged, after generation 100, past the 5 this run has done" in err


def test_retention_never_deletes_a_link_or_a_fifo_named_as_an_older_checkpoint(run, tmp_path):
    """A link or a FIFO named as an older checkpoint is not one of the run's files: retention leaves
    it (and what a link points at) alone, and deletes only the run's own older checkpoint."""
    ckpts = run / "checkpoints"
    outside = tmp_path / "outside.json.gz"
    outside.write_bytes(b"kept")
    (ckpts / "gen-00000.json.gz").symlink_to(outside)
    os.mkfifo(ckpts / "gen-00001.json.gz")
    RunDir(run).save_checkpoint(4, {"method": "sgr"})
    assert sorted(f.name for f in ckpts.iterdir()) == ["gen-00000.json.gz", "gen-00001.json.gz",
                                                      "gen-00003.json.gz", "gen-00004.json.gz"]
    assert outside.read_bytes() == b"kept"


def test_a_file_name_with_terminal_escapes_is_printed_escaped(run, tmp_path, capsys):
    """A planted file named with an escape sequence (one that retitles the terminal) reached the
    terminal raw in the warning line; now its control characters are printed as \\x1b, \\x07."""
    from evolve.runs.checkpoint import load_checkpoint

    attack = Attack(tmp_path)
    (run / "checkpoints" / "\x1b]0;pwned\x07gen.pkl").write_bytes(b"\x80planted")
    with attack.watching(run):
        state = load_checkpoint(RunDir(run))
    assert state["generation"] == GENERATIONS
    err = capsys.readouterr().err
    assert "\x1b" not in err and "\x07" not in err
    assert "\\x1b]0;pwned\\x07gen.pkl (a pickle, never loaded)" in err


def test_an_error_line_naming_a_folder_with_terminal_escapes_is_printed_escaped(run, tmp_path, capsys):
    """`sgr: error:` lines escape control characters in one place (evolve/cli main): a run folder
    named with an escape sequence and a damaged champion.json give one line, no raw ESC."""
    from tsim.errors import printable

    attack = Attack(tmp_path)
    odd = run.parent / "\x1b[2Jrun"
    run.rename(odd)
    (odd / "champion.json").write_text("{")
    with attack.watching(odd.parent):
        r = attack.main("render", str(odd), capsys=capsys, timeout=BOUND)
    line = r.error_line()
    assert "\x1b" not in r.err
    assert f"{printable(odd)}/champion.json: not valid JSON" in line and "\\x1b[2Jrun" in line


def test_printable_escapes_c0_del_and_c1_and_nothing_else():
    """`printable` writes C0, DEL and C1 characters as \\xNN and leaves all else (accents too)."""
    from tsim.errors import printable

    assert printable("a\x1b]0;x\x07\n\t\x7f\x9bé ok") == "a\\x1b]0;x\\x07\\x0a\\x09\\x7f\\x9bé ok"


# ------------------------------------------------------------ champion.json, config.yaml, generations.csv


@pytest.mark.parametrize("command", ["render", "report"])
@pytest.mark.parametrize("kind", ["fifo", "devzero", "outside"])
def test_a_champion_json_that_is_a_fifo_or_a_link_is_refused_in_one_line(run, tmp_path, capsys, command,
                                                                           kind):
    """champion.json as a FIFO or linked to /dev/zero (a hang or all the memory) or to a champion
    outside the folder (shown as this run's): `sgr render` and `sgr report` end with one line
    naming the file."""
    attack = Attack(tmp_path)
    plant(kind, run / "champion.json", attack, real=run / "champion.json")
    args = [command, str(run)] + (["--no-robustness", "--no-gallery", "--out", str(tmp_path / "r.md")]
                                  if command == "report" else ["--out", str(tmp_path / "c.gif")])
    with attack.watching(run):
        r = attack.main(*args, capsys=capsys, timeout=BOUND)
    line = r.error_line()
    what = "a symbolic link, which sgr does not follow" if kind == "outside" else "not a regular file"
    assert line.startswith(f"sgr: error: {run / 'champion.json'}: {what}"), line


@pytest.mark.parametrize("args", [("evolve", "--resume"), ("select-champion",)])
def test_a_config_yaml_that_is_a_fifo_is_refused_in_one_line_naming_it(run, tmp_path, capsys, args):
    """config.yaml as a FIFO: every command that reads a run's config says so in one line (it was
    "not a run directory (no config.yaml)", which sent the user looking for a missing file)."""
    attack = Attack(tmp_path)
    (run / "config.yaml").unlink()
    os.mkfifo(run / "config.yaml")
    with attack.watching(run):
        r = attack.main(*args, str(run), capsys=capsys, timeout=BOUND)
    assert r.error_line() == f"sgr: error: {run / 'config.yaml'}: not a regular file (a FIFO)"


def test_a_generations_csv_that_is_a_fifo_is_refused_by_report_in_one_line(run, tmp_path, capsys):
    """generations.csv as a FIFO: `sgr report` names it in one line (it was taken for a folder with
    no generations.csv, and the run left out of the report)."""
    attack = Attack(tmp_path)
    (run / "generations.csv").unlink()
    os.mkfifo(run / "generations.csv")
    with attack.watching(run):
        r = attack.main("report", str(run), "--no-robustness", "--no-gallery", "--out",
                        str(tmp_path / "r.md"), capsys=capsys, timeout=BOUND)
    assert r.error_line() == f"sgr: error: {run / 'generations.csv'}: not a regular file (a FIFO)"


def test_a_config_yaml_linked_outside_the_run_is_refused_not_followed(run, tmp_path, capsys):
    """config.yaml linked to a file outside the run (another run's settings, shown as this one's):
    refused in one line naming it; the run's config is never read through a link."""
    attack = Attack(tmp_path)
    elsewhere = tmp_path / "other.yaml"
    elsewhere.write_text(yaml.safe_dump(yaml.safe_load((run / "config.yaml").read_text())))
    (run / "config.yaml").unlink()
    (run / "config.yaml").symlink_to(elsewhere)
    with attack.watching(run):
        r = attack.main("render", str(run), capsys=capsys, timeout=BOUND)
    assert r.error_line() == (f"sgr: error: {run / 'config.yaml'}: a symbolic link, which sgr does not "
                              "follow inside a folder")


# ------------------------------------------------------------------ sgr validate's data folder


@pytest.mark.parametrize("kind", ["fifo", "devzero", "folder"])
def test_validate_refuses_an_index_json_that_is_a_fifo_or_a_device_in_one_line(tmp_path, capsys, kind):
    """`sgr validate DIR` read DIR/index.json whatever it was: a FIFO blocked it, a link to /dev/zero
    filled the memory. A data set's files are read through links (git-annex), but only regular
    ones: each of these ends in one line naming index.json."""
    attack = Attack(tmp_path)
    data = tmp_path / "traces"
    data.mkdir()
    index = data / "index.json"
    if kind == "fifo":
        os.mkfifo(index)
    elif kind == "devzero":
        index.symlink_to("/dev/zero")
    else:
        index.mkdir()  # a folder of that name
    with attack.watching(data):
        r = attack.main("validate", str(data), capsys=capsys, timeout=BOUND)
    what = {"fifo": "a FIFO", "devzero": "a character device", "folder": "a folder"}[kind]
    assert r.error_line() == f"sgr: error: {index}: not a regular file ({what})"


# ------------------------------------------------------------------ the reader itself


def test_the_reader_refuses_what_is_not_a_regular_file_in_one_line_naming_it(tmp_path, monkeypatch):
    """`read_bytes`: a FIFO returns at once (refused), so do a socket and a device, a link inside a
    folder is refused unless the caller follows links (a file the user names), and a file over the
    cap is refused."""
    import socket

    from tsim.files import read_bytes

    monkeypatch.chdir(tmp_path)  # (a socket's path must be short)
    with socket.socket(socket.AF_UNIX) as sock:
        sock.bind("sock")
        with pytest.raises(SgrError, match=r"sock: not a regular file \(a socket\)$"):
            read_bytes(tmp_path / "sock", 10)
    with pytest.raises(SgrError, match=r"^/dev/null: not a regular file \(a character device\)$"):
        read_bytes("/dev/null", 10, follow=True)

    os.mkfifo(tmp_path / "fifo")
    (tmp_path / "real").write_bytes(b"12345")
    (tmp_path / "link").symlink_to(tmp_path / "real")
    with pytest.raises(SgrError, match=r"fifo: not a regular file \(a FIFO\)$"):
        read_bytes(tmp_path / "fifo", 10)
    with pytest.raises(SgrError, match=r"link: a symbolic link, which sgr does not follow inside a folder$"):
        read_bytes(tmp_path / "link", 10)
    assert read_bytes(tmp_path / "link", 10, follow=True) == b"12345"
    with pytest.raises(SgrError, match=r"real: over 4 bytes, more than sgr reads in such a file$"):
        read_bytes(tmp_path / "real", 4)
    assert json.loads(read_bytes(tmp_path / "real", 5)) == 12345


@pytest.mark.parametrize("kind", ["fifo", "outside"])
def test_a_neat_ini_that_is_a_fifo_or_a_link_is_refused_by_resume_in_one_line(run, tmp_path, capsys, kind):
    """neat.ini as a FIFO was "no such config file" to neat-python (which opens it itself), a file
    that is there; linked outside the run it was read as the run's own. Both: one line naming it
    and what it is, before anything is read."""
    attack = Attack(tmp_path)
    plant(kind, run / "neat.ini", attack, real=run / "neat.ini")
    with attack.watching(run):
        r = attack.main("evolve", "--resume", str(run), "--generations", "4", capsys=capsys, timeout=BOUND)
    what = "not a regular file (a FIFO)" if kind == "fifo" else "a symbolic link, which sgr does not follow"
    assert r.error_line().startswith(f"sgr: error: {run / 'neat.ini'}: {what}"), r.err
