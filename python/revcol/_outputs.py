"""No output of a run names one of its inputs, nor another of its outputs (issue 59): the one
check every command runs on its outputs before anything runs or is written.

A run's *inputs* are its scene file, the scene's ``[system] initial_state``, the checkpoint it
resumes from (``revcol simulate --resume``), and for ``revcol sweep`` the sweep file and its
scene; its *outputs* are files (the JSON report, the trajectory) and folders (figures,
checkpoints, a sweep's table and points), each folder with the names its writer puts there.
:func:`refuse_collisions` compares them all, each path in two places: resolved through symlinks
(``os.path.realpath``; a file that does not exist yet resolves by its folder), and as named with
its folder resolved (every writer moves a finished file over that name, so a symlink named as an
output would be replaced); two files that exist are also compared by ``os.path.samefile`` (hard
links, case-insensitive file systems). It refuses, with one line naming both roles and the path:

- an output that is an input;
- a folder output that would write an input: a name its writer produces (``checkpoint-<count>.npz``
  for a count the run can reach, ``energy_drift.png``), not any file that lives there;
- two outputs that name one file (or a file that a folder output would write).

:func:`check_outputs` then checks the outputs' size (:func:`check_sizes`): each output may carry
an estimate of the bytes its writer will write over the run (:class:`Size`, from
:mod:`revcol._output_size`), and a run whose outputs come to more than the output limit
(``--max-output`` / ``[output] max_output``, :data:`DEFAULT_MAX_OUTPUT` unless told) or more than
the free space of the file system they go to is refused with one line naming the largest writer,
its estimate and the limit or the free space. Last, each output must be writable (not a folder
where a file goes or the reverse, its folder created and a file written there on trial).
"""
from __future__ import annotations

import os
import re
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Iterable, Sequence

from ._args import size as _size
from .scene_schema import SceneError

if TYPE_CHECKING:
    from .scene import Scene

__all__ = ["Output", "Input", "Size", "checkpoint_names", "run_inputs", "refuse_collisions", "check_outputs",
           "check_sizes", "output_limit", "human", "estimates", "DEFAULT_MAX_OUTPUT"]

#: the output limit of a run unless ``--max-output`` or ``[output] max_output`` says otherwise: 10 GiB,
#: far above what the example scenes write (kilobytes to a few megabytes) and far below a full disk
DEFAULT_MAX_OUTPUT = 10 << 30

#: the name every checkpoint writer gives its files: ``checkpoint-<net collisions, 12 digits>.npz``
_CHECKPOINT = re.compile(r"checkpoint-(\d{12,})\.npz")


@dataclass(frozen=True)
class Size:
    """The bytes an output's writer is estimated to write over the run, and how they were counted
    (``"2,003 frames of 1,000 particles, about 105 bytes a particle"``)."""

    bytes: float
    how: str


@dataclass(frozen=True)
class Output:
    """One output of a run: ``what`` names it in messages (``"[output] json / --json"``); a
    ``folder`` writes the file names in ``names``, or those ``match`` accepts (None and None: none);
    ``size``: the estimate of its bytes (None: not estimated)."""

    what: str
    path: str | os.PathLike | None
    folder: bool = False
    names: frozenset[str] | None = None
    match: Callable[[str], bool] | None = None
    size: Size | None = None

    def writes(self, name: str) -> bool:
        """Whether this folder's writer may put a file called ``name`` in it."""
        if self.names is not None and name in self.names:
            return True
        return self.match is not None and self.match(name)


@dataclass(frozen=True)
class Input:
    """One input file of a run: ``what`` says which (``"the scene file itself"``)."""

    what: str
    path: str | os.PathLike


def checkpoint_names(first: int = 0, last: int | None = None, every: int | None = None) -> Callable[[str], bool]:
    """The checkpoint names a run may write: ``checkpoint-<n>.npz`` for first <= n <= last (no end:
    None), n a multiple of ``every`` when given."""
    def match(name: str) -> bool:
        m = _CHECKPOINT.fullmatch(name)
        if m is None:
            return False
        n = int(m.group(1))
        return (name == f"checkpoint-{n:012d}.npz" and n >= first and (last is None or n <= last)
                and (not every or n % every == 0))
    return match


def run_inputs(scene: "Scene", resume: str | os.PathLike | None = None) -> list[Input]:
    """The input files of a scene's run: the scene file (when it is one), its initial state, and
    the checkpoint it resumes from."""
    out = []
    if scene.source and Path(scene.source).is_file():
        out.append(Input("the scene file itself", scene.source))
    if scene.initial_state is not None:
        out.append(Input("the run's initial state file ([system] initial_state)", scene.initial_state))
    if resume is not None:
        out.append(Input("the checkpoint the run resumes from (--resume)", resume))
    return out


def _path(o: Output) -> str:
    """The path of an output that has one (the others are dropped before any comparison)."""
    assert o.path is not None
    return os.fspath(o.path)


def _places(path: str | os.PathLike) -> tuple[str, str]:
    """``path`` resolved through symlinks, and as named with its folder resolved."""
    a = os.path.abspath(os.fspath(path))
    return os.path.realpath(a), os.path.join(os.path.realpath(os.path.dirname(a)), os.path.basename(a))


def _same(a: str | os.PathLike, b: str | os.PathLike) -> bool:
    if set(_places(a)) & set(_places(b)):
        return True
    try:
        return os.path.samefile(a, b)
    except OSError:  # one of them does not exist (yet)
        return False


def _written_in(folder: Output, path: str | os.PathLike) -> str | None:
    """The file in ``folder`` that its writer may write and that is ``path``, or None."""
    real = os.path.realpath(os.path.abspath(_path(folder)))
    for place in dict.fromkeys(_places(path)):
        name = os.path.basename(place)
        if folder.writes(name):
            there = os.path.join(real, name)
            if os.path.dirname(place) == real or _same(there, path):
                return there
    return None


def _named(path: str | os.PathLike) -> str:
    """``path`` as given, and where it leads when a symlink moves it."""
    real, given = os.path.realpath(os.path.abspath(os.fspath(path))), os.path.abspath(os.fspath(path))
    return os.fspath(path) + (f" (through symlinks {real})" if real != given else "")


def refuse_collisions(source: str, outputs: Iterable[Output], inputs: Sequence[Input],
                      error: type[Exception] = SceneError) -> None:
    """Raises ``error`` (one line: ``source``, both roles, the path) when an output is or would
    write an input, or two outputs name one file. Creates nothing."""
    outs = [o for o in outputs if o.path is not None]
    for o in outs:
        for i in inputs:
            if _same(_path(o), i.path):
                raise error(f"{source}: {o.what}: {_named(_path(o))} is {i.what}: refusing to overwrite an input "
                            "of the run")
            there = _written_in(o, i.path) if o.folder else None
            if there is not None:
                raise error(f"{source}: {o.what}: would write {there}, which is {i.what} ({os.fspath(i.path)}): "
                            "refusing to overwrite an input of the run")
    for k, a in enumerate(outs):
        for b in outs[k + 1:]:
            there = _clash(a, b)
            if there is not None:
                raise error(f"{source}: {a.what} and {b.what} both write {there}: refusing to write two outputs "
                            "of the run to one file")


def _clash(a: Output, b: Output) -> str | None:
    """The file two outputs would both write, or None."""
    if _same(_path(a), _path(b)):
        if a.folder and b.folder:  # one folder for two writers: a clash only where their names meet
            if a.match is not None and b.match is not None:  # two open-ended writers: taken as meeting
                return _named(_path(a))
            for x, y in ((a, b), (b, a)):
                common = sorted(n for n in (x.names or ()) if y.writes(n))
                if common:
                    return os.path.join(os.path.realpath(_path(a)), common[0])
            return None
        return _named(_path(a))
    for folder, other in ((a, b), (b, a)):
        if folder.folder and not other.folder:
            there = _written_in(folder, _path(other))
            if there is not None:
                return there
    return None


def _check_writable(source: str, o: Output, error: type[Exception]) -> None:
    """Raises ``error`` naming ``o`` unless it can be written: not a folder where a file goes (or the
    reverse), its folder creatable and writable (tried)."""
    p = Path(_path(o)).resolve()
    if o.folder and p.exists() and not p.is_dir():
        raise error(f"{source}: {o.what}: {p} exists and is not a folder")
    if not o.folder and p.is_dir():
        raise error(f"{source}: {o.what}: {p} is a folder, not a file")
    parent = p if o.folder else p.parent
    try:
        parent.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=parent):
            pass
    except OSError as e:
        raise error(f"{source}: {o.what}: cannot write into {parent} ({e.strerror or e})") from None


def human(n: float) -> str:
    """Bytes in binary units, three digits: ``"1.5 GiB"``, ``"91 TiB"``, ``"512 B"``."""
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB"):
        if abs(n) < 1024 or unit == "PiB":
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.3g} {unit}"
        n /= 1024
    raise AssertionError


def output_limit(source: str, given, scene_value: int | None) -> int:
    """The output limit in bytes (0: none): ``given`` (``--max-output``: bytes, or a string such as
    ``"20G"`` or ``"none"``), else the scene's ``[output] max_output``, else :data:`DEFAULT_MAX_OUTPUT`.
    A bad value raises SceneError naming ``--max-output``."""
    if given is None:
        return DEFAULT_MAX_OUTPUT if scene_value is None else scene_value
    try:
        return _size(given, "--max-output")
    except ValueError as e:
        raise SceneError(f"{source}: {e}") from None


def _existing(path: Path) -> Path:
    """``path`` or its nearest folder that exists (an output's folder may not be made yet)."""
    p = path.resolve()
    while not p.exists() and p != p.parent:
        p = p.parent
    return p


def _over(o: Output, total: float, many: bool, there: str = "") -> str:
    """The start of a refusal: the largest writer, its estimate, and the run's total (``there``)."""
    assert o.size is not None
    rest = f"; the run's outputs{there} come to about {human(total)}" if many and total > o.size.bytes else ""
    return f"{o.what} would write about {human(o.size.bytes)} ({o.size.how}){rest}"


def check_sizes(source: str, outputs: Iterable[Output], limit: int | None = None,
                error: type[Exception] = SceneError, flag: str = "--max-output or [output] max_output") -> None:
    """Raises ``error`` (one line) when the outputs' estimated bytes, summed, exceed ``limit``
    (None: :data:`DEFAULT_MAX_OUTPUT`; 0: no limit), or when those going to one file system exceed
    its free space (``shutil.disk_usage`` of the output's folder, or of its nearest existing parent).
    ``flag``: where the limit is set, for the message. Creates nothing."""
    sized = [o for o in outputs if o.path is not None and o.size is not None]
    if not sized:
        return
    limit = DEFAULT_MAX_OUTPUT if limit is None else limit
    total = sum(o.size.bytes for o in sized if o.size is not None)
    big = max(sized, key=lambda o: o.size.bytes if o.size is not None else 0.0)
    if limit and total > limit:
        raise error(f"{source}: {_over(big, total, len(sized) > 1)}: more than the output limit of {human(limit)} "
                    f"({flag}: a size such as 20G, or none): refusing to start")
    places: dict[int, tuple[Path, list[Output]]] = {}
    for o in sized:
        where = _existing(Path(_path(o)) if o.folder else Path(_path(o)).parent)
        places.setdefault(os.stat(where).st_dev, (where, []))[1].append(o)
    for where, outs in places.values():
        need = sum(o.size.bytes for o in outs if o.size is not None)
        free = shutil.disk_usage(where).free
        if need > free:
            big = max(outs, key=lambda o: o.size.bytes if o.size is not None else 0.0)
            raise error(f"{source}: {_over(big, need, len(outs) > 1, ' on that file system')}: more than the "
                        f"{human(free)} free on the file system of {where}: refusing to start")


def estimates(outputs: Iterable[Output]) -> dict[str, dict[str, Any]]:
    """The estimated sizes, for a report: ``{what: {"path", "bytes", "how"}}`` of each output with both."""
    return {o.what: {"path": os.fspath(o.path), "bytes": int(round(o.size.bytes)), "how": o.size.how}
            for o in outputs if o.path is not None and o.size is not None}


def check_outputs(source: str, outputs: Iterable[Output], inputs: Sequence[Input],
                  error: type[Exception] = SceneError, max_output: int | None = None) -> None:
    """Every output of a run checked before it runs: :func:`refuse_collisions`, then the sizes
    against ``max_output`` (None: :data:`DEFAULT_MAX_OUTPUT`; 0: no limit) and the free space
    (:func:`check_sizes`; nothing created when either refuses), then each one writable (its
    folder created)."""
    outs = [o for o in outputs if o.path is not None]
    refuse_collisions(source, outs, inputs, error)
    check_sizes(source, outs, max_output, error)
    for o in outs:
        _check_writable(source, o, error)
