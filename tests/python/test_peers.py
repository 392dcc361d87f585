"""The peer benchmark's parts that need no peer (bench/peers/fs_edmd.py, issue 21): the source
patches, the state file, the fluid check, and the clear message when the peer is absent."""
import importlib.util
import os
import subprocess

import numpy as np
import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
SPEC = importlib.util.spec_from_file_location("fs_edmd", os.path.join(HERE, "..", "..", "bench", "peers", "fs_edmd.py"))
fs = importlib.util.module_from_spec(SPEC)
SPEC.loader.exec_module(fs)

# the lines of the peer's mdSingle.c (commit 2d0c862) that the benchmark patches, in context
PEER_LIKE = """#include <stdio.h>
#include <string.h>
double maxtime = 100;
double writeinterval = 1;
const int usethermostat = 1;
int main()
{
    init();
    while (simtime <= maxtime)
    {
      step();
    }
    simtime = maxtime;
}
"""


def test_patch_source_turns_off_the_thermostat_and_times_a_fixed_number_of_collisions():
    out = fs.patch_source(PEER_LIKE, 2000, 50000)
    assert "const int usethermostat = 0;" in out and "usethermostat = 1" not in out
    assert "double writeinterval = 1e30;" in out and "double maxtime = 1e30;" in out
    assert "#include <time.h>" in out and "clock_gettime(CLOCK_MONOTONIC" in out
    assert "long long warm = 2000, timed = 50000;" in out and "REVCOL_PEER" in out
    assert "while (simtime <= maxtime)" not in out


def test_patch_source_names_a_patch_that_does_not_match_this_peer():
    with pytest.raises(ValueError, match="usethermostat"):
        fs.patch_source(PEER_LIKE.replace("const int usethermostat = 1;", ""), 1, 1)
    with pytest.raises(ValueError, match="found 2"):
        fs.patch_source(PEER_LIKE + "double maxtime = 100;\n", 1, 1)


def test_sph_file_round_trip(tmp_path):
    rng = np.random.default_rng(3)
    box = np.array([7.5, 7.5, 7.5])
    x = rng.uniform(0, 7.5, size=(40, 3))
    path = str(tmp_path / "init.sph")
    fs.write_sph(path, x, box)
    y, b = fs.read_sph(path)
    assert np.array_equal(y, x) and np.array_equal(b, box)  # 17 significant digits: exact
    with open(path) as fh:
        lines = fh.read().splitlines()
    assert lines[0] == "40" and lines[2].startswith("a ") and lines[2].endswith(" 0.5")
    assert not os.path.exists(path + ".part")


def test_structure_factor_tells_a_crystal_from_a_fluid():
    m, a = 4, 1.6  # 4 m^3 = 256 FCC sites, lattice constant a
    cell = np.array([[0, 0, 0], [0.5, 0.5, 0], [0.5, 0, 0.5], [0, 0.5, 0.5]])
    x = np.array([(np.array([i, j, k]) + c) * a for i in range(m) for j in range(m) for k in range(m) for c in cell])
    box = np.full(3, m * a)
    k = fs.fcc_bragg_vectors(len(x), box)
    assert np.allclose(fs.structure_factor(x, k), len(x))  # every Bragg peak: S = N
    gas = np.random.default_rng(5).uniform(0, m * a, size=x.shape)
    assert fs.structure_factor(gas, k).max() < 10.0  # no order: S ~ 1 (exponential, mean 1)
    with pytest.raises(ValueError, match="4 m\\^3"):
        fs.fcc_bragg_vectors(1000, box)


def test_wrapped_folds_into_the_box():
    box = np.array([2.0, 3.0, 4.0])
    x = np.array([[-1e-17, 3.0, 9.0], [2.5, -0.5, 3.999]])
    y = fs.wrapped(x, box)
    assert np.all(y >= 0) and np.all(y < box)
    assert np.allclose(y[1], [0.5, 2.5, 3.999])


def test_missing_peer_says_where_its_source_goes_and_measures_nothing(tmp_path, capsys):
    out = tmp_path / "peer.json"
    assert fs.main(["--src", str(tmp_path / "nowhere"), "--json", str(out)]) == 0
    said = capsys.readouterr().out
    assert "git clone https://github.com/FSmallenburg/EDMD" in said and "2d0c862" in said
    assert not out.exists()


def test_peer_commit_is_not_revcols_for_an_unpacked_archive_inside_its_tree(tmp_path):
    # an archive unpacked inside a git repository (as bench/peers/src/EDMD inside revcol's)
    repo = tmp_path / "outer"
    inner = repo / "bench" / "peers" / "src" / "EDMD"
    inner.mkdir(parents=True)
    subprocess.run(["git", "init", "-q", str(repo)], check=True)
    (repo / "f").write_text("x")
    subprocess.run(["git", "-C", str(repo), "-c", "user.name=t", "-c", "user.email=t@t", "add", "f"], check=True)
    subprocess.run(["git", "-C", str(repo), "-c", "user.name=t", "-c", "user.email=t@t", "commit", "-q", "-m", "m"],
                   check=True)
    assert fs.peer_commit(str(inner)) == "unknown (not a git checkout)"
    # its own checkout: its own commit
    subprocess.run(["git", "init", "-q", str(inner)], check=True)
    (inner / "g").write_text("y")
    subprocess.run(["git", "-C", str(inner), "-c", "user.name=t", "-c", "user.email=t@t", "add", "g"], check=True)
    subprocess.run(["git", "-C", str(inner), "-c", "user.name=t", "-c", "user.email=t@t", "commit", "-q", "-m", "m"],
                   check=True)
    want = subprocess.run(["git", "-C", str(inner), "rev-parse", "--short", "HEAD"], capture_output=True,
                          text=True).stdout.strip()
    assert fs.peer_commit(str(inner)) == want
    assert fs.peer_commit(str(tmp_path / "nowhere")) == "unknown (not a git checkout)"


BSPEC = importlib.util.spec_from_file_location(
    "fs_edmd_builds", os.path.join(HERE, "..", "..", "bench", "peers", "fs_edmd_builds.py"))
builds = importlib.util.module_from_spec(BSPEC)
BSPEC.loader.exec_module(builds)


def test_builds_benchmark_without_the_peer_says_where_it_goes_and_measures_nothing(tmp_path, capsys):
    out = tmp_path / "builds.json"
    assert builds.main(["--src", str(tmp_path / "nowhere"), "--build", "installed=", "--json", str(out)]) == 0
    assert "git clone https://github.com/FSmallenburg/EDMD" in capsys.readouterr().out
    assert not out.exists()


@pytest.mark.parametrize("arg, said", [("nameonly", "NAME=PATH"), ("=somewhere", "NAME=PATH"),
                                       ("old=/no/such/folder", "no revcol package in /no/such/folder")])
def test_builds_benchmark_names_a_bad_build_argument(tmp_path, capsys, arg, said):
    with pytest.raises(SystemExit) as e:
        builds.main(["--src", str(tmp_path / "nowhere"), "--build", arg])
    assert e.value.code == 2
    assert said in capsys.readouterr().err


def test_lattice_and_float_children_run_a_small_fluid_forward_and_back(tmp_path):
    """The children the table runs, on a 256-sphere fluid (the benchmark's own state maker):
    rates are positive, and the lattice engine's run back ends on its starting bits."""
    st = fs.equilibrated_state(256, 0.3, 20.0)
    assert st["fluid"]
    npz = tmp_path / "state.npz"
    np.savez(npz, x=st["x"], v=st["v"], box=st["box"])
    lat = fs.run_lattice(str(npz), 500, 2000, -1)
    assert lat["bit_exact"] is True
    assert lat["forward"] > 0 and lat["reverse"] > 0
    flo = fs.run_revcol(str(npz), 500, 2000, -1)
    assert flo["forward"] > 0 and flo["reverse"] > 0


def test_lattice_child_reports_a_bad_state_by_name(tmp_path):
    """An overlapping start is refused by the lattice engine's own check, and the harness says
    which child failed instead of printing a rate."""
    x = np.array([[1.0, 1.0, 1.0], [1.5, 1.0, 1.0]] + [[3.0 + 1.2 * i, 5.0, 5.0] for i in range(4)])
    v = np.zeros_like(x)
    v[:, 0] = 1.0
    npz = tmp_path / "bad.npz"
    np.savez(npz, x=x, v=v, box=np.full(3, 10.0))
    with pytest.raises(RuntimeError, match=r"lattice child failed[\s\S]*particles 0 and 1 overlap"):
        fs.run_lattice(str(npz), 10, 10, -1)


PSPEC = importlib.util.spec_from_file_location("peer_profile", os.path.join(HERE, "..", "..", "bench", "peers", "profile.py"))
prof = importlib.util.module_from_spec(PSPEC)
PSPEC.loader.exec_module(prof)

ENGINE = "revcol::engine::detail::EngineImpl<3, revcol::ops::Exact3D>::"


@pytest.mark.parametrize("chain, part", [
    # an inlined pair test, then the prediction it sits in
    (["revcol::engine::FloatKinematics<3>::pair_test2(int)", ENGINE + "predict(int)"], "prediction"),
    ([ENGINE + "predict(int)"], "prediction"),
    (["revcol::engine::EventQueue<double>::sift_down(int)"], "queue"),
    (["revcol::Pair3DExact::forward(...) const"], "operator + RNG"),
    (["revcol::rng::philox4x32_10(...)", ENGINE + "draw(int, unsigned long&, bool)"], "operator + RNG"),
    # a helper no part claims goes by its caller: near() in a renewal, and in collide's pair image
    (["revcol::engine::NeighbourLists<3>::near(int, int, unsigned int&) const",
      "revcol::engine::NeighbourLists<3>::rebuild_list(int)"], "renewal"),
    (["revcol::engine::NeighbourLists<3>::near(int, int, unsigned int&) const",
      "revcol::engine::NeighbourLists<3>::pair_shift(int, int) const", ENGINE + "collide(int, int, double, bool)"],
     "bookkeeping"),
    (["revcol::engine::NeighbourLists<3>::renew(int)"], "renewal"),
    (["std::vector<int>::operator[](unsigned long)", ENGINE + "loop(...)"], "bookkeeping"),
    (["memcpy"], "other"),
    ([], "other"),
])
def test_profile_puts_a_revcol_sample_in_the_part_of_its_innermost_claimed_function(chain, part):
    assert prof.part_of(chain, "revcol") == part


LATTICE = ("revcol::lattice::BasicEngine<revcol::lattice::LatticePair3D, revcol::lattice::BitsBack, "
           "revcol::engine::EventQueue<long> >::")


@pytest.mark.parametrize("chain, part", [
    # the exact search inlined into the prediction's scan; the filter's own lines
    (["revcol::lattice::first_overlap(std::array<long, 3ul> const&, ...)", LATTICE + "scan(int, long, Best&)"],
     "prediction: exact search"),
    ([LATTICE + "scan(int, long, Best&)", LATTICE + "predict(int, long)"], "prediction: filter"),
    # a generic helper (pos) goes by its caller: the acceptance scan, the filter, the loop
    ([LATTICE + "pos(int, long) const", LATTICE + "post_reason(int, int, ...) const"], "acceptance scans"),
    ([LATTICE + "pos(int, long) const", LATTICE + "loop(...)"], "bookkeeping"),
    (["revcol::lattice::BitsBack::push_rans(unsigned long, unsigned long)",
      "revcol::lattice::LatticePair3D::forward(...) const", LATTICE + "collide_drawn(int, int, long, bool)"],
     "operator + bits-back"),
    (["revcol::lattice::draw48(unsigned int, unsigned int, unsigned long)", LATTICE + "collide_drawn(...)"],
     "operator + bits-back"),
    ([LATTICE + "group_collide(int, int, long, ...)"], "group + redraws"),
    (["revcol::engine::EventQueue<long>::sift_up(int)", LATTICE + "schedule(int, Type, long, int, int)"], "queue"),
    ([LATTICE + "schedule(int, Type, long, int, int)", LATTICE + "predict(int, long)"], "queue"),
    (["revcol::lattice::NeighbourListsN<3ul>::renew(int, std::array<long, 3ul> const&)", LATTICE + "loop(...)"],
     "renewal"),
    (["memcpy"], "other"),
])
def test_profile_puts_a_lattice_sample_in_the_part_of_its_innermost_claimed_function(chain, part):
    assert prof.part_of(chain, "lattice") == part


@pytest.mark.parametrize("chain, part", [
    (["findcollision", "findcollisions", "collision"], "prediction"),  # inlined into the collision
    (["update", "collision"], "bookkeeping"),
    (["collision"], "operator + RNG"),
    (["removeevent", "step"], "queue"),
    (["makeneighborlist"], "renewal"),
    (["collisions_of_something_else"], "other"),  # exact names only
])
def test_profile_puts_a_peer_sample_in_the_part_of_its_innermost_claimed_function(chain, part):
    assert prof.part_of(chain, "fs") == part


def test_profile_reads_the_samples_of_one_binary_from_perf_script(tmp_path):
    core = tmp_path / "_core.so"
    core.write_text("")
    out = "\n".join([
        f"    7f00aa001234 _ZN6revcol7predictEi+0x1b3 ({core})",
        f"    7f00aa001235 _ZN6revcol7predictEi+0x1b3 ({core})",
        f"    7f00aa001300 _ZN6revcol4loopEv+0x10 ({core})",
        "    55550000abcd _PyEval_EvalFrameDefault+0x99 (/usr/bin/python3.11)",
        f"    7f00aa009999 [unknown] ({core})",
        "garbage line",
    ])
    hits, total = prof.parse_samples(out, str(core))
    assert total == 5
    assert hits == {("_ZN6revcol7predictEi", 0x1b3): 2, ("_ZN6revcol4loopEv", 0x10): 1, ("[unknown]", -1): 1}


def test_profile_turns_shares_into_ns_per_collision():
    ns = prof.ns_per_part({"prediction": 30, "queue": 10, "other": 0}, 800.0)
    assert ns == {"prediction": 600.0, "queue": 200.0, "other": 0.0}
    assert prof.ns_per_part({"prediction": 0}, 800.0) == {"prediction": 0.0}


def test_profile_reads_callgrind_annotate_and_puts_instructions_per_collision_in_parts():
    ann = "\n".join([
        "--------------------------------------------------------------------------------",
        "6,716,013,181 (100.0%)  PROGRAM TOTALS",
        "Ir                      file:function",
        f"1,441,492,207 (21.46%)  ???:{LATTICE}predict(int, long) [/w/build-dev/revcol-bench]",
        "  342,833,214 ( 5.10%)  ???:revcol::lattice::boundary(long) [/w/build-dev/revcol-bench]",
        "   25,848,923 ( 0.38%)  ./math/../sysdeps/ieee754/dbl-64/e_asin.c:__ieee754_asin_fma [/usr/lib/libm.so.6]",
        "   10,000,000 ( 0.10%)  ???:revcol::lattice::boundary(long) [/w/other.so]",
    ])
    own = prof.parse_annotate(ann)
    assert own == {LATTICE + "predict(int, long)": 1441492207, "revcol::lattice::boundary(long)": 352833214,
                   "__ieee754_asin_fma": 25848923}
    small = {LATTICE + "predict(int, long)": 1000, "revcol::lattice::boundary(long)": 500, "setup_only": 7000}
    large = {LATTICE + "predict(int, long)": 3000, "revcol::lattice::boundary(long)": 1500, "setup_only": 7000,
             "__ieee754_asin_fma": 100}
    parts = prof.parts_of_counts(small, large, 10, "lattice")
    assert parts["prediction: filter"] == 200.0 and parts["operator + bits-back"] == 100.0
    assert parts["other"] == 10.0 and sum(parts.values()) == 310.0  # the setup cancels
    assert set(parts) == set(prof.LATTICE_PARTS)


def test_profile_without_the_peer_says_where_it_goes_and_measures_nothing(tmp_path, capsys):
    out = tmp_path / "profile.json"
    assert prof.main(["--src", str(tmp_path / "nowhere"), "--json", str(out)]) == 0
    assert "git clone https://github.com/FSmallenburg/EDMD" in capsys.readouterr().out
    assert not out.exists()


MSPEC = importlib.util.spec_from_file_location("peer_memory", os.path.join(HERE, "..", "..", "bench", "peers", "memory.py"))
mem = importlib.util.module_from_spec(MSPEC)
MSPEC.loader.exec_module(mem)


def test_memory_without_the_peer_says_where_it_goes_and_measures_nothing(tmp_path, capsys):
    out = tmp_path / "memory.json"
    assert mem.main(["--src", str(tmp_path / "nowhere"), "--json", str(out)]) == 0
    assert "git clone https://github.com/FSmallenburg/EDMD" in capsys.readouterr().out
    assert not out.exists()


@pytest.mark.parametrize("engine", ["lattice", "float"])
def test_memory_child_reports_its_resident_set_and_the_engines_count(tmp_path, engine):
    st = mem.start(64, 0.3)
    npz = tmp_path / "s.npz"
    np.savez(npz, **st)
    r = mem.child_memory(engine, str(npz), 1.0)
    assert r["rss"] > 10 * 2**20  # an interpreter with numpy and revcol loaded
    assert 64 * 100 < r["engine_bytes"] < r["rss"]
