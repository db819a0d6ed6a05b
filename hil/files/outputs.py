"""Writing outputs: whole files or nothing, so an interrupted write never leaves half a result.

Every file hil writes for a user (models, results, reports, samples, figures, exports) goes through
`atomic_write_text` / `atomic_write_bytes`: a temporary file beside the target, then a rename.

Before a command computes, moves or writes anything it checks each output path with `check_output`
(`check_output_dir` for a directory of outputs): a rename onto a path that is one of the command's
inputs or the campaign database would silently replace it (``hil show last --db s.db
--export-measurements s.db`` once turned the store into a CSV), so such a path is bad input, as is a
directory or a path whose folder does not exist.
"""

from __future__ import annotations

import csv
import io
import os
import stat
import tempfile
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path

import numpy as np

from hil.errors import InputError
from hil.files.inputs import file_kind

PathArg = str | os.PathLike[str]

#: Files beside an SQLite database that belong to it (write-ahead log, rollback journal, shared memory).
STORE_SIDECARS: tuple[str, ...] = ("", "-wal", "-journal", "-shm")


def _same_file(a: PathArg, b: PathArg) -> bool:
    """Whether `a` and `b` name one file: the same inode when both exist (hard links, symlinks), else
    the same path once symlinks and ``..`` are resolved (an output naming a store not created yet)."""
    try:
        if os.path.samefile(a, b):
            return True
    except (OSError, ValueError):
        pass
    try:
        return os.path.realpath(a) == os.path.realpath(b)
    except (OSError, ValueError):
        return False


def _is_url(path: PathArg) -> bool:
    """A store given as a URL (a database server) is no file an output could overwrite."""
    return "://" in os.fspath(path)


def check_output(path: PathArg, *, field: str,
                 inputs: Mapping[str, PathArg | None] | Iterable[tuple[str, PathArg | None]] = (),
                 store: PathArg | None = None, store_field: str = "--db",
                 outputs: Mapping[str, PathArg | None] | Iterable[tuple[str, PathArg | None]] = (),
                 ) -> Path:
    """`path` as a Path when it can take an output of option `field`, else a one-line InputError.

    Refused, so a typo never costs a user's data: the path of an input (`inputs`: option -> path,
    compared by inode, so hard links and symlinks count), the store (`store`, the database of
    `store_field`, or its -wal/-journal/-shm), another output of the same command (`outputs`), an
    existing directory, and a path whose parent directory does not exist. Call it before anything is
    computed, moved or written.
    """
    name = os.fspath(path)
    target = Path(name)
    if not name:
        raise InputError(f"{field}: empty path; name a file")
    _check_name_length(target, field)  # first: stat() of a name too long fails with ENAMETOOLONG
    if target.is_dir():
        raise InputError(f"{field}: {name} is a directory; name a file")
    if name.endswith(os.sep) or (os.altsep and name.endswith(os.altsep)):
        raise InputError(f"{field}: {name} ends in a slash, which names a directory; name a file")
    parent = target.parent
    if not parent.is_dir():
        what = "is not a directory" if parent.exists() else "does not exist"
        raise InputError(f"{field}: cannot write {name}: folder {parent} {what}")
    try:
        mode = os.stat(target).st_mode
    except OSError:
        mode = None  # not there yet (or a dangling link, which the rename replaces)
    if mode is not None and not stat.S_ISREG(mode):
        raise InputError(f"{field}: {name} is {file_kind(mode)}, not a regular file: hil writes a result to "
                         "a file, whole, so it could not be read back; name a file")
    for option, other in _pairs(inputs):
        if _same_file(target, other):
            raise InputError(f"{field}: {name} is the input {option}; writing it would destroy it, "
                             "choose another file")
    if store is not None and not _is_url(store):
        for suffix in STORE_SIDECARS:
            if _same_file(target, os.fspath(store) + suffix):
                what = "the store" if not suffix else f"the store's {suffix[1:]} file"
                raise InputError(f"{field}: {name} is {what} ({store_field} {os.fspath(store)}); "
                                 "choose another file")
    for option, other in _pairs(outputs):
        if _same_file(target, other):
            raise InputError(f"{field}: {name} is also the output {option}; give each its own file")
    return target


def _check_name_length(target: Path, field: str) -> None:
    """InputError when the file system would refuse `target`'s name or path as too long (ENAMETOOLONG
    at the write, after the work was done): the limits are the file system's own (pathconf)."""
    parent = target.parent if target.parent.is_dir() else Path(".")
    try:
        name_max = os.pathconf(parent, "PC_NAME_MAX")
        path_max = os.pathconf(parent, "PC_PATH_MAX")
    except (OSError, ValueError):
        name_max, path_max = 255, 4096  # POSIX's usual values, when the file system does not say
    length = len(os.fsencode(target.name))
    if length > name_max:
        raise InputError(f"{field}: the file name {target.name[:40]}... is {length} bytes long; this file "
                         f"system allows at most {name_max}")
    if len(os.fsencode(os.path.abspath(target))) >= path_max:
        raise InputError(f"{field}: the path {os.fspath(target)[:40]}... is longer than this file system "
                         f"allows ({path_max} bytes)")


def check_output_dir(path: PathArg, *, field: str, names: Iterable[str] = (),
                     inputs: Mapping[str, PathArg | None] | Iterable[tuple[str, PathArg | None]] = (),
                     store: PathArg | None = None, store_field: str = "--db") -> Path:
    """`path` as a Path when it can take a command's outputs (created if missing), else InputError.

    Refused: an existing file (not a directory), a missing directory whose parent does not exist, and
    (for the file `names` the command writes into it) anything `check_output` refuses.
    """
    name = os.fspath(path)
    target = Path(name)
    if not name:
        raise InputError(f"{field}: empty path; name a directory")
    _check_name_length(target, field)
    if target.exists() and not target.is_dir():
        raise InputError(f"{field}: {name} is a file, not a directory; name a directory")
    if not target.exists() and not target.parent.is_dir():
        raise InputError(f"{field}: cannot create {name}: folder {target.parent} does not exist")
    if target.is_dir():  # a directory still to be created holds no input yet
        for file in names:
            check_output(target / file, field=field, inputs=inputs, store=store, store_field=store_field)
    return target


def _pairs(items: Mapping[str, PathArg | None] | Iterable[tuple[str, PathArg | None]]
           ) -> list[tuple[str, PathArg]]:
    """(option, path) pairs of a mapping or an iterable of pairs, without the options not given."""
    pairs = items.items() if isinstance(items, Mapping) else items
    return [(option, p) for option, p in pairs if p is not None and os.fspath(p) != ""]


def atomic_write_text(path: str | os.PathLike[str], text: str) -> None:
    """Write `text` to `path` via a temporary file and rename, so a failure leaves no partial file."""
    atomic_write_bytes(path, text.encode("utf-8"))


def atomic_write_bytes(path: str | os.PathLike[str], data: bytes) -> None:
    """`atomic_write_text` for bytes (figures)."""
    target = Path(path)
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=target.parent, prefix=f".{target.name[:64]}.", suffix=".tmp")
    except OSError as exc:
        raise InputError(f"{target}: cannot write: {exc.strerror or exc}") from None
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes 0600; a result is as readable as any file
        os.replace(tmp, target)
    except OSError as exc:  # a full disk, a quota, a file system gone read-only: the user's to fix
        Path(tmp).unlink(missing_ok=True)
        raise InputError(f"{target}: cannot write: {exc.strerror or exc}") from None
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def format_csv(header: Sequence[str], rows: np.ndarray) -> str:
    """CSV text with `header` and full-precision float rows."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(header)
    for row in np.asarray(rows, dtype=float):
        writer.writerow([repr(float(v)) for v in row])
    return out.getvalue()
