"""The lattice state per particle from Python: one bits-back integer and one collision count per
particle in snapshots and checkpoints, the rare log keyed by (particle, count), and a checkpoint
of the older layout (one X for the gas, the log keyed by the global index) refused by name and
restarted from its physical state by ``restart_from_legacy``."""
import numpy as np
import pytest

from revcol.lattice import LatticeSimulation, restart_from_legacy


def _bit_length(words: np.ndarray) -> int:
    return int(sum(int(w) << (64 * k) for k, w in enumerate(words)).bit_length())


def _per_particle(s: dict) -> list:
    sizes = np.asarray(s["bits_size"], dtype=np.int64)
    starts = np.concatenate([[0], np.cumsum(sizes)])
    return [np.asarray(s["bits"])[starts[k]:starts[k + 1]] for k in range(sizes.size)]


@pytest.mark.parametrize("boundary", ["periodic", "wall"])
def test_one_x_and_one_count_per_particle_in_the_snapshot(boundary):
    sim = LatticeSimulation.random(n=200, phi=0.5, boundary=boundary, seed=4, tick_bits=16)
    s0 = sim.snapshot()
    assert [_bit_length(w) for w in _per_particle(s0)] == [128] * 200
    sim.run(collisions=20_000)
    s = sim.snapshot()
    words = _per_particle(s)
    assert len(words) == 200 and sum(len(w) for w in words) == len(s["bits"])
    assert sim.diagnostics()["bits_length"] == sum(_bit_length(w) for w in words)
    # each pair collision counts for its two particles, each group for its members
    extra = int(np.sum(np.asarray(s["group_size"], dtype=np.int64) - 2))
    assert int(np.sum(s["particle_collisions"])) == 2 * sim.collisions + extra
    assert len(s["log_particle"]) + len(s["group_drawer"]) == sim.diagnostics()["log_entries"] > 0
    for p, c in zip(s["log_particle"], s["log_count"]):
        assert 1 <= c <= s["particle_collisions"][p]
    sim.run_back()
    back = sim.snapshot()
    for k in ("bits", "bits_size", "particle_collisions", "streams", "x", "v"):
        assert np.array_equal(back[k], s0[k]), k


def _older_layout(s: dict) -> dict:
    """The snapshot as an older revcol wrote it: one 256-bit X, the log keyed by the global index."""
    old = {k: v for k, v in s.items() if k not in (
        "bits_size", "particle_collisions", "log_particle", "log_count", "group_draws", "group_counts")}
    old["bits"] = np.array([3, 1, 4, 1 << 63], dtype=np.uint64)
    old["log_index"] = np.zeros(0, dtype=np.uint64)
    old["log_redraws"] = np.zeros(0, dtype=np.uint64)
    old["group_index"] = np.zeros(0, dtype=np.uint64)
    return old


def test_an_older_checkpoint_is_refused_by_name_and_restarts_from_its_state(tmp_path):
    sim = LatticeSimulation.random(n=150, phi=0.4, boundary="wall", seed=6)
    sim.run(collisions=4000)
    s = sim.snapshot()
    old = _older_layout(s)
    with pytest.raises(ValueError, match="older revcol.*restart_from_legacy"):
        LatticeSimulation.from_snapshot(old)
    # through a file too: the checkpoint's own stamps kept, its entries of the older layout
    sim.save(tmp_path / "new.npz")
    with np.load(tmp_path / "new.npz") as z:
        data = {k: z[k] for k in z.files}
    for k in ("bits_size", "particle_collisions", "log_particle", "log_count", "group_draws", "group_counts",
              "digest_sha256"):  # an older revcol wrote no digest either
        del data[k]
    data.update(bits=old["bits"], log_index=old["log_index"], log_redraws=old["log_redraws"],
                group_index=old["group_index"])
    np.savez(tmp_path / "old.npz", **data)
    with pytest.raises(ValueError, match="restart_from_legacy"):
        LatticeSimulation.load(tmp_path / "old.npz")
    for source in (old, tmp_path / "old.npz"):
        new = restart_from_legacy(source)
        assert new.collisions == 0 and new.clock == sim.clock and new.mode == sim.mode
        assert np.array_equal(new.lattice_positions, sim.lattice_positions)
        assert np.array_equal(new.lattice_velocities, sim.lattice_velocities)
        t = new.snapshot()
        assert np.array_equal(t["streams"], s["streams"])  # the streams go on where they were
        new.run(collisions=3000)
        new.run_back()
        u = new.snapshot()
        assert all(np.array_equal(u[k], t[k]) for k in ("x", "v", "streams", "bits", "particle_collisions", "clock"))
    with pytest.raises(ValueError, match="current layout"):
        restart_from_legacy(s)
