"""The tampers of the checkpoint property run (:mod:`revcol.studies.fuzz_checkpoints`, whose
docstring lists them): each rewrites a saved ``.npz`` in one of the twelve ways and says what it
did."""
from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np


def per_particle(arrays: dict, n: int) -> list:
    return [k for k, a in arrays.items() if a.ndim >= 1 and a.shape[0] in (n, 2 * n, 3 * n) and a.size > 0
            and k not in ("box", "boundary", "momentum0", "counters", "trace")]


def tamper(path: Path, kind: str, rng: np.random.Generator, n: int) -> dict:
    """Applies ``kind`` to the checkpoint at ``path``; returns what it did."""
    from revcol._io import DIGEST_KEY, digested

    if kind == "none":
        return {}
    raw = path.read_bytes()
    if kind == "truncate_file":
        cut = int(rng.integers(0, len(raw)))
        path.write_bytes(raw[:cut])
        return {"cut_to": cut, "of": len(raw)}
    if kind == "flip_file_byte":
        at = int(rng.integers(0, len(raw)))
        b = bytearray(raw)
        b[at] ^= int(rng.integers(1, 256))
        path.write_bytes(bytes(b))
        return {"byte": at, "of": len(raw)}
    with np.load(path, allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files}
    keys = sorted(k for k in arrays if k != DIGEST_KEY)
    redigest, info = True, {}
    if kind == "redigest_same":
        pass
    elif kind in ("flip_keep_digest", "flip_redigest"):
        cands = [k for k in keys if arrays[k].nbytes > 0]
        k = str(rng.choice(cands))
        a = np.ascontiguousarray(arrays[k]).copy()
        flat = a.reshape(-1).view(np.uint8)
        at = int(rng.integers(0, flat.size))
        flat[at] ^= np.uint8(1 << int(rng.integers(0, 8)))
        arrays[k] = a
        redigest = kind == "flip_redigest"
        info = {"entry": k, "byte": at}
    elif kind == "dtype":
        k = str(rng.choice(keys))
        a = arrays[k]
        to = str(rng.choice(["<f8", "<f4", "<i8", "<i4", "<u8", "|b1", "<U8"]))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                arrays[k] = a.astype(to)
            except (ValueError, TypeError, OverflowError):
                arrays[k] = np.zeros(a.shape, dtype=to)
        info = {"entry": k, "from": a.dtype.str, "to": to}
    elif kind == "shape":
        k = str(rng.choice(keys))
        a = arrays[k]
        how = str(rng.choice(["cut", "extend", "reshape", "scalar_to_1d", "empty"]))
        flat = a.reshape(-1)
        if how == "cut" and flat.size:
            arrays[k] = flat[: int(rng.integers(0, flat.size))]
        elif how == "extend":
            arrays[k] = np.concatenate([flat, flat[:1] if flat.size else np.zeros(1, a.dtype)])
        elif how == "reshape" and flat.size:
            arrays[k] = flat.reshape(flat.size, 1) if a.ndim != 2 else flat
        elif how == "scalar_to_1d":
            arrays[k] = flat.reshape(1, -1)
        else:
            arrays[k] = np.zeros((0,), a.dtype)
        info = {"entry": k, "how": how, "from": list(a.shape), "to": list(arrays[k].shape)}
    elif kind == "drop_entry":
        k = str(rng.choice(keys))
        del arrays[k]
        redigest = rng.random() < 0.8
        info = {"entry": k, "redigest": redigest}
    elif kind == "add_entry":
        name = str(rng.choice(["extra", "x2", "units.extra", "quantization.extra", "trace_v2", "a.b.c"]))
        arrays[name] = np.asarray(rng.integers(-5, 5, size=int(rng.integers(0, 4))))
        info = {"entry": name}
    elif kind == "scalar":
        cands = [k for k in keys if arrays[k].ndim == 0]
        k = str(rng.choice(cands))
        a = arrays[k]
        choice = int(rng.integers(0, 9))
        if a.dtype.kind in "iub":
            v = int(a)
            vals = [0, -1, v + 1, v - 1, 2 * v, 2**63 - 1, -2**63, 7, 2**62]
            new = np.asarray(vals[choice]) if a.dtype.kind != "u" else np.asarray(abs(vals[choice]) % 2**64, np.uint64)
        elif a.dtype.kind == "f":
            fv = float(a)
            fvals = [0.0, -1.0, np.nextafter(fv, np.inf), np.nextafter(fv, -np.inf), 2 * fv, 1e300, np.nan, np.inf, -fv]
            new = np.asarray(fvals[choice], dtype=a.dtype)
        else:
            new = np.asarray(["", "lattice", "float", "exact", "specular", "paper", "x" * 70, "periodic", "0"][choice])
        arrays[k] = new
        info = {"entry": k, "to": str(new)[:40]}
    elif kind == "swap_particles":
        cands = per_particle(arrays, n)
        if n < 2 or not cands:
            info = {"skipped": "no per-particle entry"}
        else:
            i, j = (int(x) for x in rng.choice(n, size=2, replace=False))
            which = cands if rng.random() < 0.5 else [str(rng.choice(cands))]
            for k in which:
                a = arrays[k].copy()
                per = a.shape[0] // n
                rows = a.reshape(n, per, *a.shape[1:])
                rows[[i, j]] = rows[[j, i]]
                arrays[k] = rows.reshape(a.shape)
            info = {"particles": [i, j], "entries": which}
    else:
        raise ValueError(f"unknown tamper {kind!r}")
    out = digested(arrays) if redigest else arrays
    with open(path, "wb") as f:
        np.savez(f, **out)
    return info
