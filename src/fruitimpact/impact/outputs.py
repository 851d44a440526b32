"""Writing the user's files safely: checked before any work, written atomically.

Every file fruitimpact writes for a user (tables, curves, figures, run
outputs) goes through this module:

* ``check_output(path, argument, formats)`` is called before any computing
  starts.  It refuses, with one line naming the argument, an unsupported
  extension, a directory, a missing or read-only folder, and a name too long
  for the file system, so that a long run never ends in a traceback.
* ``atomic_write(path, write)`` writes to a temporary file beside ``path``
  and renames it into place: a kill, a full disk or an error leaves either
  the old file or the new one, never half of one.  The temporary file's name
  marks it as fruitimpact's own (``.NAME.fruitimpact-tmp-PID-HEX``), so that
  ``remove_stale_temporaries`` can delete the leftovers of a killed run, and
  only those.
"""

from __future__ import annotations

import errno
import json
import math
import os
import re
import uuid
from pathlib import Path

#: Figure formats by extension (matplotlib chooses the writer from it).
FIGURE_FORMATS = {".png": "png", ".svg": "svg", ".pdf": "pdf"}
#: Table formats by extension.
TABLE_FORMATS = {".csv": "csv", ".parquet": "parquet", ".pq": "parquet"}
#: Curves and JSON-lines outputs that are only ever CSV.
CSV_FORMAT = {".csv": "csv"}

_TMP_MARK = ".fruitimpact-tmp-"
#: Room kept in a name for the temporary suffix (``.fruitimpact-tmp-PID-HEX`` plus a leading dot).
_TMP_ROOM = len(_TMP_MARK) + 1 + 10 + 1 + 8 + 1


def _label(argument: str) -> str:
    return f"argument {argument}" if argument.startswith("-") else argument


def output_error(argument: str, path, reason: str) -> ValueError:
    """The one-line error about output ``path`` given as ``argument``."""
    return ValueError(f"{_label(argument)}: cannot write {str(path)!r}: {reason}")


def output_format(path, argument: str, formats: dict[str, str]) -> str:
    """The format of ``path`` by its extension; ``ValueError`` naming the allowed ones."""
    suffix = Path(path).suffix.lower()
    if suffix not in formats:
        allowed = ", ".join(formats)
        shown = f"'{suffix}'" if suffix else "no extension"
        raise output_error(argument, path, f"unsupported format {shown} (allowed: {allowed})")
    return formats[suffix]


def _name_max(folder: Path) -> int:
    try:
        return os.pathconf(folder, "PC_NAME_MAX")
    except (OSError, ValueError, AttributeError):
        return 255


def check_folder(folder, argument: str, path=None) -> Path:
    """``folder`` exists, is a folder and can be written in (a probe file is created and removed)."""
    folder = Path(folder)
    shown = path if path is not None else folder
    if not folder.exists():
        raise output_error(argument, shown, f"folder {str(folder)!r} does not exist")
    if not folder.is_dir():
        raise output_error(argument, shown, f"{str(folder)!r} is not a folder")
    probe = folder / f".fruitimpact-probe-{os.getpid()}-{uuid.uuid4().hex[:8]}"
    try:
        with open(probe, "xb"):
            pass
    except OSError as exc:
        raise output_error(argument, shown, _reason(exc, folder)) from None
    finally:
        try:
            probe.unlink()
        except OSError:
            pass
    return folder


def check_output_folder(folder, argument: str, create: bool = False) -> Path:
    """A folder to write files into: an existing writable folder, or one that can be made
    (its nearest existing ancestor is a writable folder).  With ``create`` it is made."""
    folder = Path(folder)
    if folder.exists():
        return check_folder(folder, argument)
    ancestor = folder.parent
    while not ancestor.exists() and ancestor != ancestor.parent:
        ancestor = ancestor.parent
    check_folder(ancestor, argument, folder)
    if create:
        try:
            folder.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise output_error(argument, folder, _reason(exc, ancestor)) from None
    return folder


def check_output(path, argument: str, formats: dict[str, str] | None = None) -> Path:
    """Check that ``path`` can be written, before any work is done.

    Parameters
    ----------
    path : str or Path
        The file to write.
    argument : str
        The option or parameter that named it (``--plot``, ``-o/--output``,
        ``path``), for the message.
    formats : dict, optional
        Allowed extensions → format names; None allows any extension.

    Returns the path.  Raises ``ValueError`` with one line otherwise.
    """
    if path is None or str(path) == "":
        raise output_error(argument, path, "empty file name")
    if str(path).endswith(("/", os.sep)):  # Path() would drop the slash and make a folder's name a file's
        raise output_error(argument, path, "the name ends in a slash (a folder); give a file name")
    path = Path(path)
    if formats is not None:
        output_format(path, argument, formats)
    folder = path.parent
    try:  # the file system's own refusals (a name too long even to look up, no permission) as the same one line
        limit = _name_max(folder if folder.is_dir() else Path("."))
        if len(path.name.encode()) + _TMP_ROOM > limit:
            raise output_error(argument, path, f"the file name is longer than this file system allows "
                                               f"({limit} bytes, with room for a temporary suffix)")
        if path.is_dir():
            raise output_error(argument, path, "it is a folder; give a file name")
        check_folder(folder, argument, path)
        if path.exists() and not os.access(path, os.W_OK):
            raise output_error(argument, path, "the file exists and is read-only")
    except OSError as exc:
        raise output_error(argument, path, _reason(exc, folder)) from None
    return path


def _reason(exc: OSError, where) -> str:
    if exc.errno == errno.ENOSPC:
        return f"no space left on the device holding {str(where)!r}"
    if exc.errno in (errno.EACCES, errno.EPERM, errno.EROFS):
        return f"no permission to write in {str(where)!r}"
    if exc.errno == errno.ENAMETOOLONG:
        return "the file name is too long for this file system"
    return exc.strerror or str(exc)


def temporary_path(path) -> Path:
    """A fresh temporary name beside ``path``, marked as fruitimpact's own."""
    path = Path(path)
    return path.with_name(f".{path.name}{_TMP_MARK}{os.getpid()}-{uuid.uuid4().hex[:8]}")


def atomic_write(path, write, argument: str = "path") -> Path:
    """Call ``write(tmp)`` on a temporary file beside ``path`` and rename it to ``path``.

    On any failure the temporary file is removed and ``path`` is untouched; an
    ``OSError`` (full disk, read-only folder) becomes a one-line ``ValueError``
    naming ``argument``.  The rename makes the write atomic against kills and
    errors; the file is not forced to the disk (fsync), which would protect it
    against a power cut too, at the price of the time to write the whole file
    through (half a second for a million-row output)."""
    path = Path(path)
    tmp = temporary_path(path)
    try:
        write(tmp)
        os.replace(tmp, path)
    except OSError as exc:
        raise output_error(argument, path, _reason(exc, path.parent)) from None
    finally:
        try:
            tmp.unlink()
        except OSError:  # gone (renamed), or the folder turned read-only: the next run removes it (marked ours)
            pass
    return path


_STALE = re.compile(r"^\.(?P<name>.+)" + re.escape(_TMP_MARK) + r"(?P<pid>\d+)-[0-9a-f]{8}$")


def process_alive(pid: int) -> bool:
    """Whether process ``pid`` is running (this one is): whose leftovers may not be removed yet."""
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def stale_temporaries(path) -> list[Path]:
    """Temporary files of ``path`` left by fruitimpact runs that are no longer alive."""
    path = Path(path)
    folder = path.parent if str(path.parent) else Path(".")
    found = []
    try:
        entries = list(folder.iterdir())
    except OSError:
        return found
    for entry in entries:
        match = _STALE.match(entry.name)
        if match and match["name"] == path.name and not process_alive(int(match["pid"])) and entry.is_file():
            found.append(entry)
    return found


def remove_stale_temporaries(path) -> int:
    """Delete the temporaries of ``path`` left by killed fruitimpact runs; returns how many."""
    removed = 0
    for entry in stale_temporaries(path):
        try:
            entry.unlink()
            removed += 1
        except OSError:
            pass
    return removed


def _json_default(value):
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return str(value)


def json_safe(obj):
    """``obj`` with NaN and infinity as None, NumPy scalars as Python numbers and tuples as lists: what strict
    JSON holds (``dump_json``'s input; the web app's answers)."""
    if type(obj).__module__ == "numpy" and hasattr(obj, "item") and getattr(obj, "ndim", 1) == 0:
        obj = obj.item()  # an np.int64 is a number, not the text "3"
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    if isinstance(obj, dict):
        return {k: json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_safe(v) for v in obj]
    return obj


def dump_json(obj, indent: int | None = 2) -> str:
    """Strict JSON of ``obj`` (the CLI's ``--json``, the web app's answers): NaN and infinity written as null,
    anything else not JSON by its text; ``indent=None``: one compact line."""
    separators = None if indent is not None else (",", ":")
    return json.dumps(json_safe(obj), indent=indent, separators=separators, default=_json_default, allow_nan=False,
                      ensure_ascii=indent is not None)


__all__ = ["CSV_FORMAT", "FIGURE_FORMATS", "TABLE_FORMATS", "atomic_write", "check_folder", "check_output", "dump_json",
           "check_output_folder", "json_safe", "process_alive",
           "output_error", "output_format", "remove_stale_temporaries", "stale_temporaries", "temporary_path"]
