"""The general exact operator from Python: laws (two independent ways), reversal, validation.

Coverage: for every named case, both laws, 5 fixed pre states (one within 1e-9 of the edge
of the pre set) and 1e5 post samples each:
(a) every chart coordinate is uniform (KS p > 0.001);
(b) independently of the chart, the post velocities have the law of rejection samples
    (uniform points on the relative-velocity sphere kept inside the cone, for flux kept with
    probability cos(eta) = |x_V| / |x|): two-sample KS on three projections, p > 0.001.
(b) is the test a wrong chart cannot pass. The seeds are fixed, so a run is reproducible; a
genuine defect gives p-values below 1e-20 at this sample size, a chance miss of the 0.001
bar a p-value near it. (With generator streams 100-104 instead of 200-204, pair3d/flux's
last state failed at p = 1e-4: the raw odd draws of CLCG4 stream 104 alone give KS p = 4e-5
at this size, and the recovered cells matched the draws exactly; hence (a) also checks the
recovered cells against U' + G exactly, which is what the chart must get right.)
"""
import numpy as np
import pytest
from scipy import stats

import revcol

N_SAMPLES = 100_000
CASES = [c for c in revcol.named_cases() if c["name"] != "pair1d"]


def helmert(n):
    h = np.zeros((n - 1, n))
    for k in range(1, n):
        h[k - 1, :k] = 1.0 / np.sqrt(k * (k + 1))
        h[k - 1, k] = -k / np.sqrt(k * (k + 1))
    return h


def constraint_matrix(case):
    """Rows a_k (unit) of the cone in Helmert coordinates, built independently of the C++."""
    n, d, pos = case["n"], case["d"], case["positions"]
    h = helmert(n)
    rows = []
    for i, j in case["contacts"]:
        r = pos[i] - pos[j]
        r = r / np.linalg.norm(r)
        rows.append(np.kron(h[:, i] - h[:, j], r) / np.sqrt(2))
    return np.array(rows), h


def pre_states(op, case):
    """Five fixed approaching pre states; the last within 1e-9 of the edge of the pre set."""
    rng = np.random.default_rng(7)
    n, d = case["n"], case["d"]
    states = []
    while len(states) < 4:
        v = rng.normal(size=(n, d))
        if all(s < 0 for s in op.normal_speeds(v)):
            states.append(v)
    # near the edge: shift a state along contact 0's normal until it barely approaches
    pos = case["positions"]
    i, j = case["contacts"][0]
    r = (pos[i] - pos[j]) / np.linalg.norm(pos[i] - pos[j])
    for v in states:
        sp = op.normal_speeds(v)
        w = v.copy()
        delta = -1e-9 - sp[0]  # target normal speed -1e-9 on contact 0
        w[i] += 0.5 * delta * r
        w[j] -= 0.5 * delta * r
        if all(s < 0 for s in op.normal_speeds(w)):
            states.append(w)
            break
    assert len(states) == 5
    return states


def rejection_samples(case, v_pre, law, count, rng):
    a, h = constraint_matrix(case)
    n, d = case["n"], case["d"]
    D = (n - 1) * d
    x_pre = np.kron(h, np.eye(d)) @ v_pre.reshape(-1)
    rho = np.linalg.norm(x_pre)
    q, _ = np.linalg.qr(a.T)  # orthonormal basis of the contacts' span V
    out = []
    while sum(len(o) for o in out) < count:
        x = rng.normal(size=(400_000, D))
        x /= np.linalg.norm(x, axis=1, keepdims=True)
        keep = np.all(x @ a.T > 0, axis=1)
        if law == "flux":
            cos_eta = np.linalg.norm(x @ q, axis=1)
            keep &= rng.random(len(x)) < cos_eta
        out.append(x[keep])
    x = rho * np.concatenate(out)[:count]
    cm = v_pre.mean(axis=0)
    v = x.reshape(-1, n - 1, d)
    return cm + np.einsum("ki,bkd->bid", h, v)  # v_i = cm + sum_k H_ki x_k


@pytest.mark.parametrize("law", ["flux", "uniform"])
@pytest.mark.parametrize("case", CASES, ids=[c["name"] for c in CASES])
def test_law_two_ways(case, law):
    op = revcol.Collision.named(case["name"], law=law)
    rng = np.random.default_rng(11)
    proj_rng = np.random.default_rng(3)
    nd = case["n"] * case["d"]
    projections = [np.eye(nd)[0], np.eye(nd)[-1], proj_rng.normal(size=nd)]
    cells = 2.0 ** op.bits
    for s, v in enumerate(pre_states(op, case)):
        gen = revcol.CLCG4(stream=200 + s)
        draws = revcol.CLCG4(stream=200 + s).next_many(N_SAMPLES * op.draws).reshape(N_SAMPLES, -1)
        post = op.forward(np.broadcast_to(v, (N_SAMPLES,) + v.shape), rng=gen)
        speeds = np.array([op.normal_speeds(p) for p in post[:2000]])
        assert np.all(speeds > 0), "post states must separate on every contact"
        # (a) chart coordinates: the recovered cell is U' + G exactly, and uniform
        c = op.chart(post)
        pre_cells = np.minimum(np.floor(op.chart(-v[None])[0] * cells), cells - 1)
        expected = (pre_cells + np.floor(draws * cells)) % cells
        offset = c * cells - expected - 0.5
        offset = (offset + cells / 2) % cells - cells / 2  # the periodic angle wraps
        assert np.abs(offset).max() < 0.25, f"{case['name']}/{law} state {s}: a cell was not recovered"
        for k in range(op.draws):
            p = stats.kstest(c[:, k], "uniform").pvalue
            assert p > 1e-3, f"{case['name']}/{law} state {s}: chart coordinate {k}: KS p = {p}"
        # (b) against rejection samples, chart-free
        ref = rejection_samples(case, v, law, N_SAMPLES, rng)
        flat, rflat = post.reshape(N_SAMPLES, -1), ref.reshape(N_SAMPLES, -1)
        for j, u in enumerate(projections):
            p = stats.ks_2samp(flat @ u, rflat @ u).pvalue
            assert p > 1e-3, f"{case['name']}/{law} state {s}: projection {j}: KS p = {p}"


def test_a_wrong_law_is_caught():
    """(b) can fail: the uniform law's samples are rejected against flux references."""
    case = next(c for c in CASES if c["name"] == "triple2d-c3")
    op = revcol.Collision.named("triple2d-c3", law="uniform")
    v = pre_states(op, case)[0]
    post = op.forward(np.broadcast_to(v, (N_SAMPLES,) + v.shape), rng=revcol.CLCG4())
    ref = rejection_samples(case, v, "flux", N_SAMPLES, np.random.default_rng(1))
    u = np.random.default_rng(3).normal(size=case["n"] * case["d"])
    ps = [stats.ks_2samp(post.reshape(N_SAMPLES, -1) @ w, ref.reshape(N_SAMPLES, -1) @ w).pvalue
          for w in (u, np.eye(6)[0], np.eye(6)[3])]
    assert min(ps) < 1e-6


@pytest.mark.parametrize("name", ["triple1d", "triple2d-c1", "chain4-2d", "triple3d-3"])
def test_reversal_draw_count_and_state(name):
    op = revcol.Collision.named(name)
    case = next(c for c in CASES if c["name"] == name)
    v = np.array(pre_states(op, case)[:4])
    gen = revcol.Philox(key=(5, 6))
    post = op.forward(v, rng=gen)
    assert gen.counter == 4 * op.draws == 4 * (case["n"] * case["d"] - case["d"] - 1)
    back = op.reverse(post, rng=gen)
    assert gen.counter == 0
    # invariants recomputed from the velocities: the cells are restored, the velocities to
    # rounding (the centre of mass and |x| are rebuilt from the post state)
    np.testing.assert_allclose(back, op.quantize(v), rtol=0, atol=1e-14 * np.abs(v).max())
    # held invariants: bit for bit
    m, e = v.sum(axis=1), (v ** 2).sum(axis=(1, 2))
    post = op.forward(v, rng=gen, momentum=m, energy=e)
    np.testing.assert_array_equal(op.reverse(post, rng=gen, momentum=m, energy=e),
                                  op.quantize(v, momentum=m, energy=e))


def test_cradle_and_validation():
    op = revcol.Collision(3, 1, [(1, 0), (2, 1)], positions=np.array([[0.0], [1.0], [2.0]]))
    v = np.array([[1.0], [0.0], [0.0]])
    assert op.normal_speeds(v) == [-1.0, 0.0]
    gen = revcol.CLCG4()
    post = op.forward(v, rng=gen)
    assert all(s > 0 for s in op.normal_speeds(post))
    np.testing.assert_allclose(op.reverse(post, rng=gen), v, atol=1e-9)
    with pytest.raises(ValueError, match="at most 3 independent contacts"):
        revcol.Collision(5, 1, [(1, 0), (2, 1), (3, 2), (4, 3)], normals=np.ones((4, 1)))
    with pytest.raises(ValueError, match="do not touch"):
        revcol.Collision(2, 2, [(0, 1)], positions=np.array([[0.0, 0.0], [2.0, 0.0]]))
    with pytest.raises(ValueError, match="same pair"):
        revcol.Collision(3, 1, [(1, 0), (0, 1)], normals=np.ones((2, 1)))
    with pytest.raises(ValueError, match="itself"):
        revcol.Collision(3, 1, [(1, 1)], normals=np.ones((1, 1)))
    with pytest.raises(ValueError, match="n >= 2"):
        revcol.Collision(1, 1, [(0, 0)], normals=np.ones((1, 1)))
    with pytest.raises(ValueError, match="separates before"):
        op.forward(np.array([[0.0], [0.0], [1.0]]), rng=gen)
    with pytest.raises(ValueError, match="shape"):
        op.forward(np.zeros((2, 1)), rng=gen)
    with pytest.raises(ValueError, match="exactly one of normals"):
        revcol.Collision(2, 1, [(0, 1)])
    assert gen.state == revcol.CLCG4().state  # nothing drawn by the failures


# chart() of separating states, as computed before the domain check (issue 59)
CHART_CASES = {
    "pair2d": ([[-0.45, -0.22], [-2.02, -0.23]], {"flux": [0.14870566769338495], "uniform": [0.2520274240873925]}),
    "triple2d-c1": ([[-0.18, 0.54], [1.94, -0.27], [-0.24, 1.0]],
                    {"flux": [0.09123430243709732, 0.288305972095718, 0.40881100131753323],
                     "uniform": [0.09123430243709732, 0.288305972095718, 0.4224032241331185]}),
    "pair3d": ([[2.04, -2.56, 0.42], [-0.57, -0.45, -0.22]],
               {"flux": [0.9628912607719851, 0.5265275866198968], "uniform": [0.8073637125876464, 0.5265275866198968]}),
}


@pytest.mark.parametrize("name", sorted(CHART_CASES))
@pytest.mark.parametrize("law", ["flux", "uniform"])
def test_chart_domain(name, law):
    """Issue 59 (the sibling of Pair2D.chart): a state with an approaching contact was charted
    (pair2d's head-on approach to 0.85); it raises naming the contact now. Separating states give
    the values they did before, and zero relative speed is refused as before."""
    op = revcol.Collision.named(name, law=law)
    v, want = CHART_CASES[name]
    v = np.array(v)
    assert op.chart(v).tolist() == want[law]
    with pytest.raises(ValueError, match=r"chart: contact \d .* approaches .normal relative velocity -"):
        op.chart(np.stack([v, v]) * np.array([1.0, -1.0])[:, None, None])
    with pytest.raises(ValueError, match="entry 1: chart: contact"):
        op.chart(np.stack([v, -v]))
    with pytest.raises(ValueError, match="zero relative speed"):
        op.chart(np.ones_like(v))
    with pytest.raises(ValueError, match="finite"):
        op.chart(np.full_like(v, np.nan))


def test_chart_of_a_state_with_one_contact_approaching():
    """One contact approaching and the others separating is outside the cone too."""
    op = revcol.Collision.named("triple2d-c1")
    v = np.array([[0.19, 1.11], [-0.21, -0.93], [0.58, 0.58]])
    assert min(op.normal_speeds(v)) < 0 < max(op.normal_speeds(v))
    with pytest.raises(ValueError, match=r"chart: contact 0 \(1, 0\) approaches"):
        op.chart(v)


def test_named_verify_cases_exact():
    for c in revcol.named_cases():
        r = revcol.verify(c["name"], collisions=2000, mode="exact", seed=1)
        assert r["passed"] and r["bit_exact"], (c["name"], r["error"])


def test_verify_pair3d_fast_is_the_engine_operator_and_bit_exact():
    """'pair3d-fast' runs Pair3DExact (the engine's 3D operator), 2 draws per collision,
    both laws and generators: bit exact back to the quantized start; bad starts are refused."""
    assert "pair3d-fast" in revcol.verify_cases("exact")
    assert "pair3d-fast" not in revcol.verify_cases("paper")
    for law in ("flux", "uniform"):
        for rng in ("clcg4", "philox"):
            r = revcol.verify("pair3d-fast", collisions=5000, law=law, rng=rng, seed=2)
            assert r["passed"] and r["bit_exact"] and r["rng_restored"], (law, rng, r["error"])
            assert r["max_rel_error"] < 1e-9
    with pytest.raises(ValueError, match="6 initial velocity components"):
        revcol.verify("pair3d-fast", collisions=10, velocities=[1.0, 0.0])
    with pytest.raises(ValueError, match="not approaching"):
        revcol.verify("pair3d-fast", collisions=10, velocities=[1.0, 1.0, 1.0, 0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="unknown case"):
        revcol.verify("pair3d-fast", collisions=10, mode="paper")


def test_batch_validates_every_entry_and_its_draws_before_anything_moves():
    """The one batch template (batch.hpp): entry and draw checks name the entry, and a bad
    batch moves no generator and writes no log; a good one draws d_n per entry and back."""
    op = revcol.Collision.named("triple1d")
    v = np.array([[[1.0], [0.0], [0.0]], [[1.0], [0.0], [0.0]]])
    assert op.draws == 1
    with pytest.raises(ValueError, match=r"^entry 1: random number must be in \[0,1\]$"):
        op.forward(v, g=[[0.5], [1.5]])
    bad = v.copy()
    bad[1] = [[0.0], [0.0], [1.0]]  # entry 1 separates: not a pre state
    gen = revcol.Philox()
    with pytest.raises(ValueError, match="^entry 1: "):
        op.forward(bad, rng=gen)
    assert gen.counter == 0 and op.log_size == 0 and op.log_pushed == 0
    post = op.forward(v, rng=gen)
    assert gen.counter == 2 * op.draws
    back = op.reverse(post, rng=gen)
    assert gen.counter == 0
    assert np.allclose(back, v)
