"""What scenes and sweeps share: reading a TOML file with one named error per way it can fail,
and the folders that hold the files shipped with revcol (found by name)."""
from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Any


def read_toml(p: Path, error: type[Exception], what: str) -> dict[str, Any]:
    """The parsed document of ``p``; ``error`` naming the file and the problem otherwise
    (missing, a folder, nested too deeply, not TOML, not text). ``what``: "scene", "sweep"."""
    try:
        return tomllib.loads(p.read_text())
    except FileNotFoundError:
        raise error(f"{p}: no such {what} file") from None
    except IsADirectoryError:
        raise error(f"{p}: is a folder, not a {what} file") from None
    except RecursionError:
        raise error(f"{p}: not a usable {what}: its arrays or tables are nested too deeply") from None
    except tomllib.TOMLDecodeError as e:
        raise error(f"{p}: not valid TOML: {' '.join(str(e).split())}") from None
    except UnicodeDecodeError as e:
        raise error(f"{p}: not a text file: {e}") from None


def shipped_dirs(folder: str, marker: str | None = None) -> list[Path]:
    """Where files shipped with revcol are found by name: the package's ``folder`` (installed
    from a wheel), else the ``folder`` of the source checkout the package is imported from (a
    development build; ``marker``, a file that must be in it, when given)."""
    here = Path(__file__).resolve().parent
    dirs = [here / folder]
    for up in here.parents[:4]:  # python/revcol, or a staged build-dev/pkg/revcol
        if (up / "pyproject.toml").is_file() and (up / folder / (marker or "")).exists():
            dirs.append(up / folder)
            break
    return [d for d in dirs if d.is_dir()]
