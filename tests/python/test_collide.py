"""Pair and wall operators from Python: laws (coverage), draw counts, reversal, validation."""
import numpy as np
import pytest
from scipy import stats

import revcol

N_DRAWS = 1_000_000


def signed_angle(post, normal):
    """eta in (-pi/2, pi/2): angle of w = v_i - v_j to the contact normal."""
    a = normal / np.linalg.norm(normal)
    t = np.array([-a[1], a[0]])
    w = post[:, 0, :] - post[:, 1, :]
    return np.arctan2(w @ t, w @ a)


@pytest.mark.parametrize("mode,law", [("exact", "flux"), ("exact", "uniform"), ("paper", "flux")])
@pytest.mark.parametrize("rng_kind", ["clcg4", "philox"])
def test_post_angle_follows_its_law(pre_states, mode, law, rng_kind):
    """10 fixed pre states x 1e6 draws: the post angle eta over the permitted half circle is
    uniform (paper mode, uniform law) or has density cos(eta)/2 (flux): KS p > 0.001."""
    for k, (v, n) in enumerate(pre_states):
        op = revcol.Pair2D(mode=mode, law=law)
        gen = revcol.CLCG4(stream=k) if rng_kind == "clcg4" else revcol.Philox(key=(k, 7))
        batch = np.broadcast_to(v, (N_DRAWS, 2, 2))
        post = op.forward(batch, n, rng=gen)
        eta = signed_angle(post, n)
        assert np.all(np.abs(eta) < np.pi / 2)
        if mode == "exact" and law == "flux":
            cdf = lambda x: (1.0 + np.sin(x)) / 2.0  # noqa: E731
        else:
            cdf = stats.uniform(loc=-np.pi / 2, scale=np.pi).cdf
        p = stats.kstest(eta, cdf).pvalue
        assert p > 1e-3, f"state {k}: KS p = {p}"
        # the chart coordinate itself is uniform under exact mode's law
        if mode == "exact":
            assert stats.kstest(op.chart(post[:100_000], n), "uniform").pvalue > 1e-3


def test_flux_and_uniform_laws_differ():
    """The test above can fail: uniform samples are rejected by the flux CDF."""
    v, n = np.array([[1.0, 0.0], [-1.0, 0.0]]), np.array([-1.0, 0.0])
    post = revcol.Pair2D(law="uniform").forward(np.broadcast_to(v, (100_000, 2, 2)), n, rng=revcol.CLCG4())
    assert stats.kstest(signed_angle(post, n), lambda x: (1 + np.sin(x)) / 2).pvalue < 1e-10


@pytest.mark.parametrize("mode", ["exact", "paper"])
def test_exactly_one_draw_per_collision_and_reversal(mode, pre_states):
    gen = revcol.CLCG4(stream=3)
    start = gen.state
    op = revcol.Pair2D(mode=mode)
    v = np.array([s[0] for s in pre_states])
    n = np.array([s[1] for s in pre_states])
    post = op.forward(v, n, rng=gen)
    ref = revcol.CLCG4(stream=3)
    for _ in range(len(v)):
        ref.next()
    assert gen.state == ref.state  # exactly len(v) numbers drawn
    back = op.reverse(post, n, rng=gen)
    assert gen.state == start
    np.testing.assert_allclose(back, op.quantize(v, n), rtol=0, atol=1e-13 * np.abs(v).max())


def test_exact_mode_bit_exact_with_held_invariants():
    op, gen = revcol.Pair2D(), revcol.Philox(key=(1, 2))
    v, n = np.array([[0.25, -0.5], [1.0, 0.75]]), np.array([1.0, 1.0])
    m, e = v.sum(axis=0), float((v ** 2).sum())
    ref = op.quantize(v, n, momentum=m, energy=e)
    x = v.copy()
    for _ in range(1000):
        x = -op.forward(x, n, rng=gen, momentum=m, energy=e)
    for _ in range(1000):
        x = op.reverse(-x, n, rng=gen, momentum=m, energy=e)
    assert np.array_equal(x, ref)


def test_given_draws_match_generator_draws():
    v, n = np.array([[0.5, 0.1], [-0.3, 0.2]]), np.array([-1.0, 0.3])
    gen = revcol.CLCG4()
    g = revcol.CLCG4().next()
    op = revcol.Pair2D()
    assert np.array_equal(op.forward(v, n, rng=gen), op.forward(v, n, g=g))


@pytest.mark.parametrize("bad,match", [
    (dict(velocities=np.zeros((3, 2))), "shape"),
    (dict(velocities=np.array([[np.nan, 0.0], [1.0, 0.0]])), "finite"),
    (dict(normal=np.array([0.0, 0.0])), "normal is zero"),
    (dict(normal=np.array([1.0, 0.0])), "not approaching"),
    (dict(velocities=np.array([[1.0, 1.0], [1.0, 1.0]])), "zero relative speed"),
])
def test_bad_input_raises_and_changes_nothing(bad, match):
    args = dict(velocities=np.array([[1.0, 0.0], [-1.0, 0.0]]), normal=np.array([-1.0, 0.0]))
    args.update(bad)
    gen = revcol.CLCG4()
    op = revcol.Pair2D()
    with pytest.raises(ValueError, match=match):
        op.forward(args["velocities"], args["normal"], rng=gen)
    assert gen.state == revcol.CLCG4().state


def test_bad_batch_entry_named_and_nothing_drawn():
    v = np.array([[[1.0, 0.0], [-1.0, 0.0]], [[-1.0, 0.0], [1.0, 0.0]]])  # entry 1 separates
    gen = revcol.Philox()
    with pytest.raises(ValueError, match="entry 1"):
        revcol.Pair2D().forward(v, [-1.0, 0.0], rng=gen)
    assert gen.counter == 0


# chart() of valid post states, as computed before the domain check (issue 59): rows i, j; normal (-1, 0)
CHART_STATES = np.array([[[-1.0, 0.0], [1.0, 0.0]], [[-1.0, 0.5], [1.0, 0.0]], [[-0.7, -2.0], [0.3, 0.25]],
                         [[0.0, 1.0], [0.0, -1.0]], [[-2.5, 1e-3], [0.5, -4.0]]])
CHART_VALUES = {"flux": [0.5, 0.3787321874818335, 0.9569057743101286, 0.0, 0.0999640086384162],
                "uniform": [0.5, 0.4220208696226307, 0.8668750612523435, 0.0, 0.20479457362354675]}


@pytest.mark.parametrize("mode", ["exact", "paper"])
@pytest.mark.parametrize("law", ["flux", "uniform"])
def test_chart_values_of_post_states_unchanged(mode, law):
    """Separating states (and the grazing one, row 3: the chart's end 0) give the values they did
    before the domain check, bit for bit; paper mode reads exact mode's chart."""
    op = revcol.Pair2D(mode=mode, law=law)
    assert op.chart(CHART_STATES, [-1.0, 0.0]).tolist() == CHART_VALUES[law]
    assert op.chart(CHART_STATES[1], [-1.0, 0.0]).tolist() == [CHART_VALUES[law][1]]


@pytest.mark.parametrize("law", ["flux", "uniform"])
@pytest.mark.parametrize("v,match", [
    ([[1.0, 0.0], [-1.0, 0.0]], "approaches along the contact normal .normal relative velocity -2 < 0"),  # was 0.5 / -0.5
    ([[1.0, -0.5], [-1.0, 0.0]], "approaches along the contact normal"),
    ([[1e-3, 0.0], [0.0, 0.0]], "approaches along the contact normal"),
    ([[0.0, 0.0], [0.0, 0.0]], "zero relative speed"),                          # was NaN (flux), 0.5 (uniform)
    ([[1.0, 1.0], [1.0, 1.0]], "zero relative speed"),
    ([[-1e-200, 0.0], [0.0, 0.0]], "relative speed too small"),                 # was NaN (flux)
    ([[np.nan, 0.0], [1.0, 0.0]], "finite"),
    ([[np.inf, 0.0], [1.0, 0.0]], "finite"),
])
def test_chart_refuses_states_outside_its_domain(law, v, match):
    """Issue 59: chart() of an approaching state returned 0.5 (flux, head-on; uniform: -0.5, outside
    [0, 1]) and NaN at zero relative velocity; both raise a ValueError naming the problem now."""
    op = revcol.Pair2D(law=law)
    with pytest.raises(ValueError, match=match):
        op.chart(np.array(v), [-1.0, 0.0])
    batch = np.stack([CHART_STATES[0], np.array(v), CHART_STATES[1]])
    with pytest.raises(ValueError, match="entry 1: .*" + match):
        op.chart(batch, [-1.0, 0.0])


def test_chart_of_forward_posts_and_of_negated_pre_states():
    """What the studies chart stays in the domain: every forward post (a draw anywhere in [0, 1])
    and the negation of every pre state."""
    rng = np.random.default_rng(11)
    v = rng.normal(size=(20_000, 2, 2))
    n = np.array([-1.0, 0.0])
    v = v[(v[:, 0] - v[:, 1]) @ n < 0]
    for law in ("flux", "uniform"):
        op = revcol.Pair2D(law=law)
        post = op.forward(v, n, g=rng.random(len(v)))
        for c in (op.chart(post, n), op.chart(-v, n)):
            assert np.all((c >= 0.0) & (c <= 1.0))


def test_exactly_one_random_source_and_valid_options():
    op = revcol.Pair2D()
    v, n = np.array([[1.0, 0.0], [-1.0, 0.0]]), [-1.0, 0.0]
    with pytest.raises(ValueError, match="exactly one"):
        op.forward(v, n)
    with pytest.raises(ValueError, match="exactly one"):
        op.forward(v, n, rng=revcol.CLCG4(), g=0.5)
    with pytest.raises(ValueError, match="mode"):
        revcol.Pair2D(mode="fast")
    with pytest.raises(ValueError, match="law"):
        revcol.Pair2D(law="cosine")
    with pytest.raises(ValueError, match="bits"):
        revcol.Pair2D(bits=64)


def test_paper_printed_reverse_fails_about_half_the_time():
    v, n = np.array([[-0.5, -0.25], [0.75, 0.5]]), np.array([1.0, 1.0])
    op = revcol.Pair2D(mode="paper", printed_reverse=True)
    batch = np.broadcast_to(v, (20_000, 2, 2))
    gen = revcol.CLCG4()
    back = op.reverse(op.forward(batch, n, rng=gen), n, rng=gen)
    wrong = np.mean(np.abs(back - v).max(axis=(1, 2)) > 1e-9)
    assert 0.45 < wrong < 0.55
    fixed = revcol.Pair2D(mode="paper")
    back = fixed.reverse(fixed.forward(batch, n, rng=gen), n, rng=gen)
    assert np.abs(back - v).max() < 1e-14


def test_rare_log_is_observable_and_served():
    op = revcol.Pair2D()
    v, n = np.array([[1e7 - 1e-3, 1e7], [1e7, 1e7]]), [1.0, 0.0]  # |cm|/|w| ~ 1e10
    gen = revcol.CLCG4()
    post = op.forward(v, n, rng=gen)
    assert op.log_size == 1 and op.log_bytes == 8 and op.log_pushed == 1
    back = op.reverse(post, n, rng=gen)
    assert op.log_size == 0
    np.testing.assert_allclose(back, v, rtol=1e-12)


def test_pair1d_and_wall():
    op = revcol.Pair1D()
    v = np.array([0.25, 1.5])
    post = op.forward(v, 1.0)
    assert post.tolist() == [1.5, 0.25]
    assert op.reverse(post, 1.0).tolist() == v.tolist()
    assert revcol.Pair1D.draws == 0 and revcol.Pair2D.draws == 1
    with pytest.raises(ValueError, match="not approaching"):
        op.forward(post, 1.0)
    w = revcol.Wall([0.0, 0.0, 0.0], [4.0, 4.0, 4.0])
    x = np.array([0.5, 3.5, 0.5])
    post = w.forward(x, np.array([-1.0, 2.0, -3.0]), 0.5)
    assert post.tolist() == [1.0, -2.0, 3.0]
    assert w.reverse(x, post, 0.5).tolist() == [-1.0, 2.0, -3.0]
    with pytest.raises(ValueError, match="does not touch"):
        w.forward(np.array([2.0, 2.0, 2.0]), np.array([1.0, 0.0, 0.0]), 0.5)
