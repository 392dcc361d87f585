"""Tests of the reversible generators through the Python API (revcol.CLCG4, revcol.Philox,
revcol.philox4x32), against /work/shared/reference/rng-vectors.md."""
import copy
import pickle

import numpy as np
import pytest

import revcol

M = (2147483647, 2147483543, 2147483423, 2147483323)
SEED = (11111111, 22222222, 33333333, 44444444)

STREAM0 = [0.90587718250437343, 0.47279111812206831, 0.36845768553167524, 0.70033861772271799,
           0.61484668235320883, 0.40032273186718703, 0.57916775835025025, 0.90917692633632563,
           0.87682302862674377, 0.035659564059150939]
STREAM1 = [0.87071393243675543, 0.46094963871096417, 0.30366232076037525, 0.34418951708168244,
           0.44760916359360575, 0.12758681500302321, 0.65220051874100049, 0.48505806243278493,
           0.68128041072774992, 0.48604248436572384]


# ------------------------------------------------------------------------------ CLCG4

def test_clcg4_stream0_vectors():
    g = revcol.CLCG4()
    assert g.state == SEED
    assert [g.next() for _ in range(10)] == STREAM0  # exact: the arithmetic is specified
    assert g.state == (2067168963, 326151508, 803323983, 320279480)


def test_clcg4_stream0_million():
    g = revcol.CLCG4(stream=0)
    a = g.next_many(10**6)
    assert g.state == (1948270257, 1257470799, 48078532, 96916113)
    assert a[-1] == 0.2989367613540953
    assert a[:10].tolist() == STREAM0


def test_clcg4_stream1_vectors():
    g = revcol.CLCG4(stream=1)
    assert g.state == (2121435502, 1887977043, 897632862, 446466865)
    assert [g.next() for _ in range(10)] == STREAM1
    assert g.state == (918989740, 856469078, 915786109, 2082021871)


def test_clcg4_jump_constants_and_substreams():
    a = revcol.CLCG4.multiplier
    b = revcol.CLCG4.inverse_multiplier
    assert revcol.CLCG4.modulus == M
    assert all(a[j] * b[j] % M[j] == 1 for j in range(4))
    a72 = tuple(pow(a[j], 2**72, M[j]) for j in range(4))
    a41 = tuple(pow(a[j], 2**41, M[j]) for j in range(4))
    assert a72 == (584425330, 1351201844, 1323813018, 28067816)
    assert a41 == (1405571282, 808907468, 587771764, 1036762801)
    for k in (0, 1, 5, 2**40 + 3):
        start = tuple(SEED[j] * pow(a72[j], k, M[j]) % M[j] for j in range(4))
        assert revcol.CLCG4(stream=k).state == start
        for s in (1, 2, 1000):
            sub = tuple(start[j] * pow(a41[j], s, M[j]) % M[j] for j in range(4))
            assert revcol.CLCG4(k, s).state == sub


def test_clcg4_round_trip_many():
    g = revcol.CLCG4(stream=3, substream=1)
    start = g.state
    a = g.next_many(10**6)
    b = g.prev_many(10**6)  # in the order undone: reversed draw order
    assert np.array_equal(b, a[::-1])
    assert g.state == start
    assert a.dtype == np.float64 and b.dtype == np.float64
    assert 0.0 <= a.min() and a.max() <= 1.0
    assert abs(a.mean() - 0.5) < 2e-3


def test_clcg4_next_prev_identity():
    g = revcol.CLCG4(stream=2)
    s0 = g.state
    u = g.next()
    assert g.prev() == u
    assert g.state == s0
    assert g.next_many(0).shape == (0,)
    with pytest.raises(ValueError):
        g.next_many(-1)


@pytest.mark.parametrize("j", range(4))
@pytest.mark.parametrize("bad", ["zero", "m", "big", "neg"])
def test_clcg4_state_setter_validates(j, bad):
    g = revcol.CLCG4(stream=4)
    g.next()
    before = g.state
    value = {"zero": 0, "m": M[j], "big": 2**40, "neg": -1}[bad]
    s = list(before)
    s[j] = value
    with pytest.raises(ValueError, match=f"s_{j}"):
        g.state = tuple(s)
    assert g.state == before


def test_clcg4_state_setter_accepts_valid_and_shape_errors():
    g = revcol.CLCG4()
    g.state = (1, 1, 1, 1)
    assert g.state == (1, 1, 1, 1)
    hi = tuple(m - 1 for m in M)
    g.state = list(hi)
    assert g.state == hi
    with pytest.raises(ValueError):
        g.state = (1, 2, 3)
    assert g.state == hi
    with pytest.raises(TypeError):
        g.state = 5
    with pytest.raises(ValueError):
        revcol.CLCG4(stream=-1)
    # copy the state to another generator: identical futures
    h = revcol.CLCG4(stream=9)
    h.state = revcol.CLCG4(stream=2).state
    assert h == revcol.CLCG4(stream=2)


def test_clcg4_repr_pickle_copy():
    g = revcol.CLCG4(stream=1)
    g.next()
    r = repr(g)
    assert r.startswith("CLCG4.from_state((") and str(g.state[0]) in r
    assert eval(r, {"CLCG4": revcol.CLCG4}) == g
    for h in (pickle.loads(pickle.dumps(g)), copy.copy(g), copy.deepcopy(g)):
        assert h.state == g.state
        assert h.next() == g.next()
        g.prev()
    assert revcol.CLCG4.__doc__ and "L'Ecuyer" in revcol.CLCG4.__doc__


# ----------------------------------------------------------------------------- Philox

@pytest.mark.parametrize(
    "counter,key,expected",
    [
        ((0, 0, 0, 0), (0, 0), "6627e8d5 e169c58d bc57ac4c 9b00dbd8"),
        ((0xFFFFFFFF,) * 4, (0xFFFFFFFF,) * 2, "408f276d 41c83b0e a20bc7c6 6d5451fd"),
        ((0x243F6A88, 0x85A308D3, 0x13198A2E, 0x03707344), (0xA4093822, 0x299F31D0),
         "d16cfe09 94fdcceb 5001e420 24126ea1"),
    ],
)
def test_philox_kat(counter, key, expected):
    out = revcol.philox4x32(counter, key)
    assert isinstance(out, tuple) and len(out) == 4
    assert " ".join(f"{w:08x}" for w in out) == expected


def test_philox4x32_bad_arguments():
    with pytest.raises(ValueError):
        revcol.philox4x32((0, 0, 0), (0, 0))
    with pytest.raises(ValueError):
        revcol.philox4x32((0, 0, 0, 2**32), (0, 0))
    with pytest.raises(ValueError):
        revcol.philox4x32((0, 0, 0, 0), (-1, 0))


def test_philox_draw_formula():
    key = (0xDEADBEEF, 42)
    p = revcol.Philox(key=key)
    assert p.key == key and p.counter == 0
    for k in (0, 1, 2**32 - 1, 2**32, 2**63 + 12345, 2**64 - 1):
        w = revcol.philox4x32((k & 0xFFFFFFFF, k >> 32, 0, 0), key)
        bits = (w[0] << 21) ^ (w[1] >> 11)
        assert p.at(k) == min((float(bits) + 0.5) * 2.0**-53, 1.0 - 2.0**-53)
        assert 0.0 < p.at(k) < 1.0


def test_philox_next_prev_counter():
    p = revcol.Philox(key=(3, 4), counter=10)
    u = p.next()
    assert u == p.at(10) and p.counter == 11
    assert p.prev() == u and p.counter == 10
    p.counter = 0
    assert p.next() == p.at(0)
    p.prev()
    with pytest.raises(ValueError, match="cannot step back before draw 0"):
        p.prev()
    assert p.counter == 0
    with pytest.raises(ValueError):
        p.counter = -1
    with pytest.raises(ValueError):
        p.counter = 2**64
    assert p.counter == 0
    p.counter = 2**64 - 1
    assert p.counter == 2**64 - 1


def test_philox_round_trip_many():
    p = revcol.Philox(key=(1, 2), counter=5)
    a = p.next_many(10**6)
    assert p.counter == 5 + 10**6
    assert np.array_equal(a[:3], [p.at(5), p.at(6), p.at(7)])
    b = p.prev_many(10**6)
    assert np.array_equal(b, a[::-1])
    assert p.counter == 5
    assert 0.0 < a.min() and a.max() < 1.0
    assert abs(a.mean() - 0.5) < 2e-3
    with pytest.raises(ValueError):
        p.prev_many(6)  # only 5 draws to undo: nothing changes
    assert p.counter == 5
    assert p.prev_many(5).tolist() == [p.at(k) for k in (4, 3, 2, 1, 0)]
    assert p.counter == 0


def test_philox_repr_pickle():
    p = revcol.Philox(key=(7, 8), counter=99)
    assert repr(p) == "Philox(key=(7, 8), counter=99)"
    assert eval(repr(p), {"Philox": revcol.Philox}) == p
    q = pickle.loads(pickle.dumps(p))
    assert q == p and q.next() == p.next()
    assert revcol.Philox() == revcol.Philox(key=(0, 0), counter=0)
    with pytest.raises(ValueError):
        revcol.Philox(key=(0, 1, 2))


def test_rng_module_reexports():
    import revcol.rng as rng

    assert rng.__all__ == ["CLCG4", "Philox", "philox4x32"]
    assert rng.CLCG4 is revcol.CLCG4 and rng.Philox is revcol.Philox
    assert rng.philox4x32 is revcol.philox4x32


def test_philox_refuses_to_wrap_its_counter():
    # issue 59: next() at counter 2^64 - 1 wrapped to 0, and prev() then refused; now refused, nothing changed
    top = 2**64 - 1
    p = revcol.Philox(key=(3, 4), counter=top)
    with pytest.raises(ValueError, match="last counter"):
        p.next()
    assert p.counter == top
    assert p.prev() == p.at(top - 1) and p.counter == top - 1
    assert p.next() == p.at(top - 1) and p.counter == top
    q = revcol.Philox(key=(3, 4), counter=top - 2)
    with pytest.raises(ValueError, match="wrap"):
        q.next_many(3)
    assert q.counter == top - 2
    assert list(q.next_many(2)) == [q.at(top - 2), q.at(top - 1)] and q.counter == top
