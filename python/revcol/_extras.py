"""Optional packages and the extra of ``pyproject.toml`` that installs each.

revcol imports matplotlib, gsd, Dask and scipy only where a figure, a GSD trajectory, a sweep or
a statistical study needs them. When one is missing, the command line says so in one line that
names the extra (``pip install 'revcol[plot]'``) and exits 2, instead of a traceback
(:func:`revcol.cli.main.main`).
"""
from __future__ import annotations

#: top-level module -> the extra that installs it
EXTRAS = {"matplotlib": "plot", "gsd": "gsd", "distributed": "sweep", "dask": "sweep", "scipy": "studies"}


def install_hint(module: str) -> str:
    """``pip install 'revcol[EXTRA]'`` for a top-level module of :data:`EXTRAS`."""
    return f"pip install 'revcol[{EXTRAS[module]}]'"


def missing_extra(e: BaseException) -> str | None:
    """The one-line message for an ImportError of an optional package, or None when ``e`` is not
    one (then it is a real error and is raised on)."""
    if not isinstance(e, ImportError):
        return None
    module = (getattr(e, "name", None) or "").split(".")[0]
    if module not in EXTRAS:
        return None
    return f"this needs {module}, which is not installed: {install_hint(module)}"
