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

:func:`check_outputs` then checks that each output can be written (not a folder where a file
goes or the reverse, its folder created and a file written there on trial).
"""
from __future__ import annotations

import os
import re
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Callable, Iterable, Sequence

from .scene_schema import SceneError

if TYPE_CHECKING:
    from .scene import Scene

__all__ = ["Output", "Input", "checkpoint_names", "run_inputs", "refuse_collisions", "check_outputs"]

#: the name every checkpoint writer gives its files: ``checkpoint-<net collisions, 12 digits>.npz``
_CHECKPOINT = re.compile(r"checkpoint-(\d{12,})\.npz")


@dataclass(frozen=True)
class Output:
    """One output of a run: ``what`` names it in messages (``"[output] json / --json"``); a
    ``folder`` writes the file names in ``names``, or those ``match`` accepts (None and None: none)."""

    what: str
    path: str | os.PathLike | None
    folder: bool = False
    names: frozenset[str] | None = None
    match: Callable[[str], bool] | None = None

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


def check_outputs(source: str, outputs: Iterable[Output], inputs: Sequence[Input],
                  error: type[Exception] = SceneError) -> None:
    """Every output of a run checked before it runs: :func:`refuse_collisions` (nothing created
    when it refuses), then each one writable (its folder created)."""
    outs = [o for o in outputs if o.path is not None]
    refuse_collisions(source, outs, inputs, error)
    for o in outs:
        _check_writable(source, o, error)
