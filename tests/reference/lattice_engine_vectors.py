"""Event-sequence vectors for the lattice engine from the prototype (LATTICE.md, reference/exactgas).

The prototype's O(N^2) engine (engine.py) runs small periodic gases of 20 disks at S = 60 with
its pair operator replaced by the deliberately simple exact test operator of
tests/cpp/test_lattice_engine.cpp (relative velocity reversed, relative position kept, centre
moved by the S-transform's s), so that the sequence of (tick, i, j) depends only on the event
rule: first integer tick at which the incoming lines overlap, ties by pair index. The C++ test
replays the same integer initial state and compares the first events.

    python tests/reference/lattice_engine_vectors.py [--exactgas DIR] [--events 300]

writes tests/data/lattice/engine_bounce_<N>_<phi>_<seed>.txt:
    S L N
    N lines: x y vx vy
    K lines: tick i j
"""
import argparse
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, '..', 'data', 'lattice')


def bounce(xi, xj, vi, vj, G, X, L, stats=None):
    """the test operator at the pair level (absolute, periodic)"""
    from exact import minimg
    r = (minimg(xi[0] - xj[0], L), minimg(xi[1] - xj[1], L))
    c = (xj[0] + (r[0] >> 1), xj[1] + (r[1] >> 1))
    d = (vi[0] - vj[0], vi[1] - vj[1])
    s = (vj[0] + (d[0] >> 1), vj[1] + (d[1] >> 1))
    c2 = (c[0] + s[0], c[1] + s[1])
    d2 = (-d[0], -d[1])
    xj2 = ((c2[0] - (r[0] >> 1)) % L, (c2[1] - (r[1] >> 1)) % L)
    xi2 = ((xj2[0] + r[0]) % L, (xj2[1] + r[1]) % L)
    vj2 = (s[0] - (d2[0] >> 1), s[1] - (d2[1] >> 1))
    vi2 = (vj2[0] + d2[0], vj2[1] + d2[1])
    return xi2, xj2, vi2, vj2, X, None


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--exactgas', default='/work/shared/reference/exactgas')
    ap.add_argument('--events', type=int, default=300)
    a = ap.parse_args()
    sys.path.insert(0, a.exactgas)
    import engine as eng
    import exact
    eng.pair_fwd = bounce
    os.makedirs(OUT, exist_ok=True)
    for N, phi, seed in ((20, 0.3, 1), (20, 0.5, 2)):
        x, v, L = eng.make_initial(N, phi, seed)
        E = eng.Engine(x, v, [0] * N, 0, L, 12345, 1 << 255)
        seq = []
        orig_step = E.step
        while len(seq) < a.events:
            # the pair about to collide: the smallest (tick, pair index) among collision predictions
            tmin = int(E.pred.min())
            flat = [k for k, t in enumerate(E.pred.ravel()) if t == tmin]
            i, j = divmod(flat[0], N)
            kind = E.kind[i, j]
            if orig_step() == 'coll':
                assert kind == eng.COLL
                seq.append((tmin, i, j))
        assert sum(E.fail.values()) == 0, E.fail
        path = os.path.join(OUT, f'engine_bounce_{N}_{phi}_{seed}.txt')
        with open(path, 'w') as f:
            f.write(f'{exact.S} {L} {N}\n')
            for (px, py), (qx, qy) in zip(x, v):
                f.write(f'{px} {py} {qx} {qy}\n')
            for t, i, j in seq:
                f.write(f'{t} {i} {j}\n')
        print('wrote', path, 'L/sigma =', L / exact.SIG, 'events', len(seq), 'last tick', seq[-1][0])


if __name__ == '__main__':
    main()
