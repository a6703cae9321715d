"""The study folder of ``omnikin sweep``: results written as tasks finish, and resumed from.

Layout of ``OUT/``::

    manifest.json                      what study the folder holds: seed, trials, points, versions
    parts/<point key>/trials-<first>-<stop>.parquet   trials first..stop-1 of a point, one file per task
    trials.parquet                     the tidy trial table (one row per trial), written at the end
    summary.parquet, summary.csv       one row per point
    figures/tolerance.png, report.md

Every file is written atomically (:func:`omnikin.io.output.atomic_write`: a temporary file beside
it, renamed when complete), so an interrupted study leaves whole parts or none. A rerun of the
same study reads which trials of which points are on disk (from the parts' contents, not their
names: a rerun with another task size still resumes) and computes only the others. A part that
cannot be read, or whose rows are not the trials its name says, is removed and computed again; so
is a part that shares a trial with another (a copy under another spelling of the name, a part
covering trials of another): parts are taken in the order of their first trial, and one that
overlaps a part already taken is removed, so every trial is read from one part only.

A folder holds one study *seed* computed by one omnikin and NumPy version: a results folder is
reused by a study of the same seed (its points, trials per point or robots may differ: parts are
kept by point key, and a point's trials ``0..n-1`` are the same whatever ``n``); another seed or
other versions are refused unless ``force`` (then, once the study is sure to run, the parts,
outputs and manifest are removed, files of other names never). A folder omnikin did not write (not
empty and no omnikin manifest) is refused, ``force`` or not. The outputs of an earlier run are
removed when a run starts (they would describe another study). Two sweeps never write one folder
at once (a lock, ``.lock``).
"""

from __future__ import annotations

import contextlib
import json
import os
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..common.messages import one_line, shorten
from ..errors import InputError, OutputError, OutputExistsError
from ..io.output import atomic_write, write_text
from ..io.textfile import read_text
from .points import point_key, result_versions
from .study import TRIAL_COLUMNS, Study

MANIFEST = "manifest.json"
PARTS = "parts"
LOCK = ".lock"
FORMAT = "omnikin sweep folder"
FORMAT_VERSION = 1
OUTPUT_FILES = ("trials.parquet", "summary.parquet", "summary.csv", "report.md", "figures/tolerance.png")
"""The files the end of a study writes (removed when a run starts: written again at its end)."""

MAX_MANIFEST_BYTES = 1 << 26
"""Largest manifest read [bytes], 64 MiB: 100 000 points of about 400 bytes each fit."""

_PART = re.compile(r"trials-(\d{6,9})-(\d{6,9})\.parquet")


def _arrow():
    import pyarrow as pa
    import pyarrow.parquet as pq

    return pa, pq


def arrow_schema(columns: Sequence[tuple[str, str]]):
    """The Arrow schema of a table whose ``columns`` are (name, Arrow type name) pairs."""
    pa, _ = _arrow()
    return pa.schema([(name, pa.type_for_alias(kind)) for name, kind in columns])


def trial_schema():
    """The Arrow schema of the trial table (:data:`~omnikin.sweep.study.TRIAL_COLUMNS`)."""
    return arrow_schema(TRIAL_COLUMNS)


def part_name(first: int, stop: int) -> str:
    """The file name of the part holding trials ``first..stop-1``."""
    return f"trials-{first:06d}-{stop:06d}.parquet"


@dataclass
class Coverage:
    """What a folder holds of a study: per point key, which trials are on disk (a bool array of
    the study's trials per point); ``removed``: damaged parts removed (computed again)."""

    done: dict[str, np.ndarray]
    removed: list[str]

    @property
    def trials(self) -> int:
        return int(sum(int(d.sum()) for d in self.done.values()))


class StudyFolder:
    """An open study folder (module docstring); use :meth:`open`, and :meth:`close` (or ``with``)."""

    def __init__(self, path: Path, study: Study, lock):
        self.path = path
        self.study = study
        self._lock = lock
        self._parts: dict[str, list[Path]] = {}
        self.stale = False

    # --- opening ---------------------------------------------------------------------------
    @classmethod
    def open(cls, path, study: Study, *, force: bool = False) -> StudyFolder:
        """Open (or create) ``path`` for ``study`` (module docstring); refuses in one line."""
        path = Path(os.fspath(path))
        if path.exists() and not path.is_dir():
            raise OutputExistsError(f"{path}: exists and is not a folder; name a folder for the study")
        if not path.exists():
            parent = path.parent if str(path.parent) else Path(".")
            if not parent.is_dir():
                raise InputError(f"{path}: cannot write: folder {parent} does not exist")
            try:
                path.mkdir()
            except FileExistsError:
                pass
            except OSError as exc:
                raise OutputError(f"{path}: cannot create: {exc.strerror or exc}") from None
        if not (path / MANIFEST).exists() and any(name != LOCK for name in os.listdir(path)):
            raise OutputExistsError(
                f"{path}: a non-empty folder omnikin did not write (no {MANIFEST}); choose a new folder"
            )
        lock = _lock(path)
        try:
            folder = cls(path, study, lock)
            folder._adopt(force)
            if not folder.stale:
                folder._write_manifest()
        except BaseException:
            _unlock(lock)
            raise
        return folder

    def _adopt(self, force: bool) -> None:
        """Take the folder over for this study, or refuse (module docstring). With ``force`` and a
        study of another seed or other versions, nothing is removed yet: :attr:`stale` is set and
        :meth:`start_over` removes that study's files once the study is sure to run."""
        self.stale = False
        manifest = self.path / MANIFEST
        if manifest.exists() or manifest.is_symlink():
            old = self._read_manifest(manifest)
            if old is None:  # a manifest.json of something else: never omnikin's to remove
                raise OutputExistsError(
                    f"{self.path}: its {MANIFEST} is not an omnikin study's; omnikin did not write this folder: "
                    "choose a new folder"
                )
            mine = result_versions()
            theirs = {name: old.get("versions", {}).get(name) for name in mine}
            if old.get("seed") != self.study.seed or theirs != mine:
                if not force:
                    held = (
                        f"a study of seed {shorten(old.get('seed'))}, this study has seed {self.study.seed}"
                        if old.get("seed") != self.study.seed
                        else f"results of omnikin {shorten(theirs['omnikin'])} with NumPy {shorten(theirs['numpy'])}, "
                        f"this is omnikin {mine['omnikin']} with NumPy {mine['numpy']}"
                    )
                    raise OutputExistsError(
                        f"{self.path}: holds {held}; choose another folder or pass --force to remove that study's "
                        "results and start over"
                    )
                self.stale = True
        self._remove_outputs()  # the tables and report of an earlier run: written again at the end

    def start_over(self) -> None:
        """Remove the results of the study the folder held (:attr:`stale`): its parts, outputs
        and manifest, and nothing else (files of other names stay, folders emptied are removed)."""
        parts = self.path / PARTS
        if parts.is_dir() and not parts.is_symlink():
            for folder in parts.iterdir():
                if not folder.is_dir() or folder.is_symlink():
                    continue
                for entry in folder.iterdir():
                    if _PART.fullmatch(entry.name) or (entry.name.startswith(".") and entry.name.endswith(".tmp")):
                        entry.unlink(missing_ok=True)
                with contextlib.suppress(OSError):
                    folder.rmdir()
            with contextlib.suppress(OSError):
                parts.rmdir()
        self.stale = False
        self._write_manifest()

    def _remove_outputs(self) -> None:
        for name in OUTPUT_FILES:
            target = self.path / name
            if target.is_file() or target.is_symlink():
                target.unlink()
        with contextlib.suppress(OSError):
            (self.path / "figures").rmdir()

    def _read_manifest(self, manifest: Path) -> dict | None:
        try:
            doc = json.loads(read_text(manifest, InputError, what="a study manifest", max_bytes=MAX_MANIFEST_BYTES))
        except (InputError, ValueError):
            return None
        if not isinstance(doc, dict) or doc.get("format") != FORMAT:
            return None
        return doc

    def _write_manifest(self) -> None:
        versions = _versions()
        study = self.study
        doc = {
            "format": FORMAT,
            "version": FORMAT_VERSION,
            "study": study.name,
            "source": study.source,
            "seed": study.seed,
            "trials": study.trials,
            "digest": study.digest,
            "versions": versions,
            "points": {point_key(p): p.as_dict() for p in study.points},
        }
        write_text(self.path / MANIFEST, json.dumps(doc, indent=1) + "\n")

    # --- parts -----------------------------------------------------------------------------
    def coverage(self) -> Coverage:
        """Which trials of the study are on disk (module docstring); removes damaged parts and
        temporary files left by an interrupted run."""
        _, pq = _arrow()
        schema = trial_schema()
        done: dict[str, np.ndarray] = {}
        removed: list[str] = []
        for point in self.study.points:
            key = point_key(point)
            have = np.zeros(self.study.trials, dtype=bool)
            done[key] = have
            self._parts[key] = []
            folder = self.path / PARTS / key
            if self.stale or not folder.is_dir():  # a stale folder's parts are another study's
                continue
            candidates: list[tuple[int, int, Path]] = []
            for entry in folder.iterdir():
                if entry.name.startswith(".") and entry.name.endswith(".tmp"):
                    entry.unlink(missing_ok=True)  # a part whose writing was cut off
                    continue
                match = _PART.fullmatch(entry.name)
                if match is not None and entry.is_file():
                    candidates.append((int(match.group(1)), int(match.group(2)), entry))
            reach = 0  # the parts taken cover trials below reach, each once
            for first, stop, entry in sorted(candidates, key=lambda c: (c[0], c[1], c[2].name)):
                problem = "overlaps another part" if first < reach else None
                if problem is None:
                    problem = _part_problem(pq, entry, schema, key, first, stop)
                if problem is not None:
                    removed.append(f"{entry}: {problem}")
                    entry.unlink(missing_ok=True)
                    continue
                reach = stop
                self._parts[key].append(entry)
                have[first : min(stop, have.size)] = True
        return Coverage(done, removed)

    def write_part(self, key: str, first: int, stop: int, columns: Mapping[str, list]) -> None:
        """Write trials ``first..stop-1`` of the point ``key`` (columns of the trial table) atomically."""
        pa, pq = _arrow()
        table = pa.Table.from_pydict(dict(columns), schema=trial_schema())
        folder = self.path / PARTS / key
        folder.mkdir(parents=True, exist_ok=True)
        target = folder / part_name(first, stop)
        with atomic_write(target, "wb") as handle:
            pq.write_table(table, handle)
        self._parts.setdefault(key, []).append(target)

    def trial_table(self, failed: Sequence[Mapping[str, list]] = ()):
        """The trial table of the study: every trial on disk of its points (trials ``< trials``)
        and the rows of ``failed`` tasks, in the order of the study's points and trials."""
        pa, pq = _arrow()
        schema = trial_schema()
        tables = [pq.read_table(part, schema=schema) for key in self._parts for part in self._parts[key]]
        tables += [pa.Table.from_pydict(dict(rows), schema=schema) for rows in failed]
        table = pa.concat_tables(tables) if tables else schema.empty_table()
        order = {point_key(p): k for k, p in enumerate(self.study.points)}
        rank = np.array([order.get(key, -1) for key in table.column("point").to_pylist()], dtype=np.int64)
        trial = table.column("trial").to_numpy()
        keep = (rank >= 0) & (trial < self.study.trials)
        table = table.filter(pa.array(keep))
        if table.num_rows:
            rows = np.lexsort((trial[keep], rank[keep]))
            ranks, trials = rank[keep][rows], trial[keep][rows]
            twice = (ranks[1:] == ranks[:-1]) & (trials[1:] == trials[:-1])
            if twice.any():  # coverage() reads each trial from one part: a row twice is a fault of omnikin
                raise RuntimeError(f"the trial table holds {int(twice.sum())} trials twice; nothing was written")
            table = table.take(pa.array(rows))
        return table

    # --- the end ---------------------------------------------------------------------------
    def write_table(self, name: str, table) -> Path:
        """Write an Arrow ``table`` as ``name`` (``.parquet`` or ``.csv``) in the folder, atomically."""
        _, pq = _arrow()
        target = self.path / name
        if name.endswith(".csv"):
            import pyarrow.csv as pcsv

            with atomic_write(target, "wb") as handle:
                pcsv.write_csv(table, handle)
        else:
            with atomic_write(target, "wb") as handle:
                pq.write_table(table, handle)
        return target

    def close(self) -> None:
        _unlock(self._lock)
        self._lock = None

    def __enter__(self) -> StudyFolder:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _versions() -> dict[str, str]:
    """The versions recorded in the manifest: those a trial's numbers depend on
    (:func:`~omnikin.sweep.points.result_versions`), Python's and Dask's."""
    import platform

    versions = {**result_versions(), "python": platform.python_version()}
    with contextlib.suppress(ImportError):
        import dask

        versions["dask"] = dask.__version__
    return versions


def _part_problem(pq, path: Path, schema, key: str, first: int, stop: int) -> str | None:
    """Why the part at ``path`` cannot be used (None if it holds exactly trials ``first..stop-1`` of ``key``)."""
    if stop <= first:
        return "names no trials"
    try:
        if not pq.read_schema(path).equals(schema):
            return "not a part of this version of the trial table"
        table = pq.read_table(path, columns=["point", "trial"])
    except Exception as exc:  # noqa: BLE001 - Arrow raises many kinds on a damaged file; each means "recompute"
        return f"unreadable ({one_line(exc, 120)})"
    trials = table.column("trial").to_numpy()
    if set(table.column("point").to_pylist()) != {key}:
        return f"rows of other points than {shorten(key)}"
    if trials.size != stop - first or not np.array_equal(np.sort(trials), np.arange(first, stop)):
        return f"rows are not trials {first} to {stop - 1}"
    return None


def _lock(path: Path):
    """An exclusive lock on the folder (``.lock``), or an error naming the folder if another sweep holds it."""
    try:
        import fcntl
    except ImportError:  # not POSIX: no lock
        return None
    try:
        handle = open(path / LOCK, "a+")  # noqa: SIM115 - held until close()
    except OSError as exc:
        raise OutputError(f"{path}: cannot write: {exc.strerror or exc}") from None
    try:
        fcntl.flock(handle.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        handle.close()
        raise OutputExistsError(
            f"{path}: another omnikin sweep is writing this folder; wait for it or choose another folder"
        ) from None
    return handle


def _unlock(handle) -> None:
    if handle is not None:
        with contextlib.suppress(OSError):
            handle.close()
