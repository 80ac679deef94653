"""Files written whole or not at all, and file-system failures as one clear message.

Every output file is written under a temporary name in its own directory, flushed to
disk, then renamed into place; on any failure the temporary is removed and a
`WriteError` names the file and the reason (read-only file system, disk full, ...), so
a reader never sees a truncated file and no stray temporaries are left.
"""
import json
import math
import os
from pathlib import Path

from femcontact.errors import InputError


class WriteError(InputError):
    """An output file or directory could not be written; the message names it and why."""


def describe(error: OSError, path) -> str:
    """'PATH: cannot write (No space left on device)'."""
    return f"{path}: cannot write ({error.strerror or error})"


def make_dir(path) -> Path:
    """mkdir -p `path`; raises WriteError naming it when that fails."""
    path = Path(path)
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise WriteError(describe(error, path)) from None
    if not path.is_dir():
        raise WriteError(f"{path}: not a directory")
    return path


def write_atomic(path, writer, binary: bool = False, sync: bool = True) -> Path:
    """Write `path` by calling `writer(stream)` on a temporary file beside it, fsync, rename.
    The temporary is removed on any failure; an OSError becomes a WriteError naming `path`.
    `sync=False` skips the fsync (7 ms under load): for bookkeeping that a rerun rewrites,
    whose loss in a power cut costs nothing."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        with open(tmp, "wb" if binary else "w", **({} if binary else {"newline": ""})) as stream:
            writer(stream)
            stream.flush()
            if sync:
                os.fsync(stream.fileno())
        os.replace(tmp, path)
    except BaseException as error:
        try:
            tmp.unlink(missing_ok=True)
        except OSError:
            pass
        if isinstance(error, OSError):
            raise WriteError(describe(error, path)) from None
        raise
    return path


def write_npz_atomic(path, compressed: bool = True, **arrays) -> Path:
    """numpy's .npz of `arrays`, built in memory and then written atomically (a zip archive
    interrupted half-way would leave an unclosable ZipFile behind)."""
    import io

    import numpy as np

    buffer = io.BytesIO()
    (np.savez_compressed if compressed else np.savez)(buffer, **arrays)
    return write_atomic(path, lambda stream: stream.write(buffer.getbuffer()), binary=True)


def write_text_atomic(path, text: str, sync: bool = True) -> Path:
    return write_atomic(path, lambda stream: stream.write(text), sync=sync)


def finite_or_none(data):
    """A copy of `data` (dicts, lists, numbers) with NaN and infinities replaced by None (JSON null)."""
    if isinstance(data, dict):
        return {key: finite_or_none(value) for key, value in data.items()}
    if isinstance(data, (list, tuple)):
        return [finite_or_none(value) for value in data]
    if isinstance(data, float) and not math.isfinite(data):
        return None
    if hasattr(data, "tolist"):  # numpy scalars and arrays
        return finite_or_none(data.tolist())
    return data


def write_json_atomic(path, data, sync: bool = True) -> Path:
    """Write JSON atomically; NaN and infinities are written as null (strict JSON)."""
    text = json.dumps(finite_or_none(data), indent=1, sort_keys=True, default=float, allow_nan=False)
    return write_text_atomic(path, text + "\n", sync=sync)


def remove_stale_compilations(directory: Path, older_than: float) -> None:
    """Delete JIT sources (and their ready marks) of FFCx's cache `directory` whose compiled
    module is missing and that are older than `older_than` seconds: a process killed while
    compiling leaves them, and every later run would wait for that compilation and time out.
    Also delete, at any age, a ready mark whose source is gone (left when a source was deleted
    mid-compilation): FFCx would write the source again, compile it, then fail to create the
    mark that already exists."""
    import time

    try:
        names = os.listdir(directory)  # once: a cache holds thousands of files
    except FileNotFoundError:
        return
    compiled = {name[:i] for name in names if name.endswith(".so") for i, c in enumerate(name) if c == "."}
    for name in names:
        source = Path(directory, name)
        if name.endswith(".c") and source.stem not in compiled:  # no STEM.so nor STEM.*.so
            try:
                stale = time.time() - source.stat().st_mtime >= older_than
            except FileNotFoundError:
                continue
            if stale:
                source.unlink(missing_ok=True)
                source.with_suffix(".c.cached").unlink(missing_ok=True)
        elif name.endswith(".c.cached") and name.removesuffix(".cached") not in names:
            source.unlink(missing_ok=True)


def read_result(case_dir: Path) -> dict | None:
    """A case's result.json, or None when it has none (not run, or interrupted)."""
    try:
        return json.loads((Path(case_dir) / "result.json").read_text())
    except (FileNotFoundError, json.JSONDecodeError):
        return None
