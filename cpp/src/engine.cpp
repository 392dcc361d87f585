// The event-driven engine: one implementation per dimension behind revcol::engine::Simulation.
// The physics and the reversal protocol are in revcol/engine/engine.hpp.
#include "revcol/engine/engine.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "revcol/collide/exact.hpp"
#include "revcol/collide/pair.hpp"
#include "revcol/collide/pair1d.hpp"
#include "revcol/collide/pair2d_exact.hpp"
#include "revcol/collide/pair2d_paper.hpp"
#include "revcol/engine/event_queue.hpp"
#include "revcol/engine/pair3d.hpp"
#include "revcol/error.hpp"
#include "revcol/rng/clcg4.hpp"
#include "revcol/rng/philox.hpp"
#include "revcol/rng/streams.hpp"

namespace revcol::engine {

Boundary parse_boundary(const std::string& s) {
  if (s == "wall") return Boundary::wall;
  if (s == "periodic") return Boundary::periodic;
  throw InvalidArgument("boundary must be 'wall' or 'periodic', got '" + s + "'");
}

Generator parse_generator(const std::string& s) {
  if (s == "philox") return Generator::philox;
  if (s == "clcg4") return Generator::clcg4;
  throw InvalidArgument("generator must be 'philox' or 'clcg4', got '" + s + "'");
}

rng::StreamPolicy parse_engine_streams(const std::string& s) {
  if (s == "per_particle" || s == "per-particle") return rng::StreamPolicy::per_particle;
  if (s == "single") return rng::StreamPolicy::single;
  throw InvalidArgument("streams must be 'per_particle' or 'single', got '" + s +
                        "' (a per-draw policy needs a fixed draw count per collision)");
}

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr int kMaxGroup = 8;  // particles in one group collision
// A renewal's new list on the stack. Listed centres are within D + shell of c_i, so their
// particles (disjoint spheres) are within D + shell + h of it: at most ((1.5 D + shell + h) /
// (D / 2))^d of them: 74 in 3D at the smallest shell (0.4 D), 45 in 2D at the shell of
// phi 0.3 (1.1 D): within kMaxList where the gas is as dense as the shell assumes. A sparse
// gas takes a wider shell, and a dense cluster in it can overflow: the slower path for more
// is the safety net.
constexpr int kMaxList = 128;

enum Kind : std::int32_t { kWall = 0, kRenew = 1, kColl = 2, kNone = 3 };  // kRenew: neighbour-list renewal

struct Ev {
  double t = kInf;
  std::int32_t kind = kNone;
  std::int32_t partner = -1;  // particle (collision), 2 axis + (v > 0) (wall) or 0 (renewal)
  std::uint64_t stamp = 0;    // the partner's stamp at prediction
};

// Lexicographic (t, kind, partner): a canonical earliest candidate whatever the scan order.
inline bool earlier(double t, std::int32_t kind, std::int32_t partner, const Ev& e) {
  if (t != e.t) return t < e.t;
  if (kind != e.kind) return kind < e.kind;
  return partner < e.partner;
}

void validate_config(const Config& c) {
  require(c.dim >= 1 && c.dim <= 3, [&] { return "dim must be 1, 2 or 3, got " + std::to_string(c.dim); });
  require(std::isfinite(c.diameter) && c.diameter > 0.0, "diameter must be finite and > 0");
  require(c.bits >= 8 && c.bits <= 52, "bits must be in [8, 52]");
  require(c.streams == rng::StreamPolicy::per_particle || c.streams == rng::StreamPolicy::single,
          "streams must be per_particle or single (a per-draw policy needs a fixed draw count per collision)");
  require(c.generator == Generator::philox || c.generator == Generator::clcg4, "generator must be philox or clcg4");
  require(std::isfinite(c.group_tol) && c.group_tol >= 0.0 && c.group_tol < 1e-3,
          "group_tol must be finite and in [0, 1e-3)");
  require(std::isfinite(c.shell) && c.shell >= 0.0, "shell must be finite and >= 0 (0: from the packing fraction)");
  require(!(c.mode == Mode::paper && c.dim == 3),
          "paper mode has no invertible 3D pair operator (Pair3DPaper is not a bijection): use exact mode in 3D");
  for (int k = 0; k < c.dim; ++k) {
    const double L = c.box[k];
    require(std::isfinite(L) && L > 0.0, [&] { return "box length on axis " + std::to_string(k) + " must be finite and > 0"; });
    if (c.boundary[k] == Boundary::wall) {
      require(L > c.diameter, [&] {
        return "diameter " + std::to_string(c.diameter) + " is too large for the box: axis " + std::to_string(k) +
               " has length " + std::to_string(L) + " (walls need L > D)";
      });
    } else {
      require(std::floor(L / c.diameter) >= 3.0, [&] {
        return "periodic box too small for the neighbour lists: axis " + std::to_string(k) + " has length " +
               std::to_string(L) + " < 3 diameters (L >= 3 D keeps each listed neighbour's nearest image "
               "unique with a shell of at least 0.45 D)";
      });
    }
  }
}

template <int Dim>
class EngineImpl final : public Simulation {
 public:
  using Vec = std::array<double, Dim>;

  EngineImpl(const Config& c, const std::vector<double>& x, const std::vector<double>& v, double t0)
      : cfg_(c), n_(x.size() / Dim), p2e_(c.law, c.bits), p3_(c.law, c.bits) {
    setup_geometry();
    p_.assign(n_, Particle{});
    for (std::size_t i = 0; i < n_; ++i) {
      for (int k = 0; k < Dim; ++k) {
        p_[i].x[k] = x[i * Dim + k];
        p_[i].v[k] = v[i * Dim + k];
      }
      p_[i].t = t0;
    }
    clock_ = t0;
    start_ = t0;
    ncoll_.assign(n_, 0);
    rng_.assign(stream_count(), 0);
    make_generators();
    cell_.assign(n_ * Dim, 0);
    set_centres(x);  // list centres: where the particles start
    ev_.assign(n_, Ev{});
    netc_.assign(n_, 0);
    second_.assign(n_, kInf);
    touching_.assign(n_, 0);
    build_lists();
    const Diagnostics d = diagnostics();
    e0_ = d.energy;
    p0_ = d.momentum;
    rebuild_events();
  }

  explicit EngineImpl(const Snapshot& s)
      : cfg_(s.config), n_(s.n), p2e_(s.config.law, s.config.bits), p3_(s.config.law, s.config.bits) {
    setup_geometry();
    p_.assign(n_, Particle{});
    for (std::size_t i = 0; i < n_; ++i) {
      for (int k = 0; k < Dim; ++k) {
        p_[i].x[k] = s.x[i * Dim + k];
        p_[i].v[k] = s.v[i * Dim + k];
      }
      p_[i].t = s.t_local[i];
      p_[i].stamp = s.stamp[i];
    }
    clock_ = s.time;
    start_ = s.start_time;
    net_ = s.net_collisions;
    ncoll_ = s.ncoll;
    require(s.rng.size() == stream_count(), "snapshot: rng must hold one draw count per stream");
    rng_ = s.rng;
    make_generators();
    cell_.assign(n_ * Dim, 0);
    // list centres (cells and lists follow from them); a checkpoint without them (written
    // before the neighbour lists) starts them where the particles are and predicts anew
    const bool old_format = s.centre.empty();
    set_centres(old_format ? positions() : s.centre);
    ev_.resize(n_);
    netc_ = s.netc;
    wkeys_ = s.wall_keys;
    wsizes_ = s.wall_sizes;
    wmasks_ = s.wall_masks;
    wids_ = s.wall_ids;
    wnetc_ = s.wall_netc;
    wtimes_ = s.wall_times;
    second_.assign(n_, kInf);
    touching_.assign(n_, 0);
    for (std::size_t i = 0; i < n_; ++i) {
      require(s.ev_kind[i] >= kWall && s.ev_kind[i] <= kNone, "snapshot: bad event kind");
      require(s.ev_kind[i] != kColl || (s.ev_partner[i] >= 0 && static_cast<std::size_t>(s.ev_partner[i]) < n_),
              "snapshot: event partner outside [0, n)");
      ev_[i] = Ev{s.ev_t[i], static_cast<std::int32_t>(s.ev_kind[i]), static_cast<std::int32_t>(s.ev_partner[i]),
                  s.ev_stamp[i]};
    }
    for (std::size_t i = 0; i < n_; ++i) {
      second_[i] = s.second[i];
      touching_[i] = s.touching[i] != 0;
    }
    for (std::uint64_t c : s.log_cells) log_.push(c);
    log_offset_ = s.log_pushed - log_.pushed();
    pre_keys_ = s.pre_keys;
    pre_sizes_ = s.pre_sizes;
    pre_vals_ = s.pre_vals;
    pre_pushed_ = s.pre_pushed;
    counters_ = s.counters;
    e0_ = s.energy0;
    p0_ = s.momentum0;
    build_lists();
    if (old_format) rebuild_events();
    else build_heap();
  }

  // ---- the Simulation interface -------------------------------------------------------

  RunResult run(std::uint64_t max_collisions, double t_end, const Progress& cb, std::uint64_t every) override {
    require(!std::isnan(t_end), "end time must not be NaN");
    return loop(max_collisions, t_end, cb, every, /*reversed=*/false);
  }

  RunResult run_back(std::uint64_t max_collisions, double t_target) override {
    require(!std::isnan(t_target), "target time must not be NaN");
    require(t_target <= clock_, [&] {
      return "run_back: target time " + std::to_string(t_target) + " is later than the current time " +
             std::to_string(clock_);
    });
    flip();
    RunResult r;
    try {
      r = loop(max_collisions, -t_target, {}, 0, /*reversed=*/true);
    } catch (...) {
      flip();
      throw;
    }
    flip();
    if (clock_ == 0.0) clock_ = 0.0;  // -0 from the negations reads as 0
    r.time = clock_;
    return r;
  }

  std::vector<double> positions() const override {
    std::vector<double> out(n_ * Dim);
    for (std::size_t i = 0; i < n_; ++i)
      for (int k = 0; k < Dim; ++k) out[i * Dim + k] = p_[i].x[k] + p_[i].v[k] * (clock_ - p_[i].t);
    return out;
  }
  std::vector<double> velocities() const override {
    std::vector<double> out(n_ * Dim);
    for (std::size_t i = 0; i < n_; ++i)
      for (int k = 0; k < Dim; ++k) out[i * Dim + k] = p_[i].v[k];
    return out;
  }
  std::vector<std::uint64_t> collision_counts() const override { return ncoll_; }
  double time() const override { return clock_; }
  double start_time() const override { return start_; }
  std::size_t size() const override { return n_; }
  const Config& config() const override { return cfg_; }

  Diagnostics diagnostics() const override {
    Diagnostics d;
    double e = 0.0;
    for (std::size_t i = 0; i < n_; ++i)
      for (int k = 0; k < Dim; ++k) {
        const double vk = p_[i].v[k];
        e += 0.5 * vk * vk;
        d.momentum[k] += vk;
      }
    d.energy = e;
    d.energy_drift = e0_ > 0 ? (e - e0_) / e0_ : 0.0;
    double dp = 0.0;
    for (int k = 0; k < Dim; ++k) dp += (d.momentum[k] - p0_[k]) * (d.momentum[k] - p0_[k]);
    d.momentum_drift = e0_ > 0 ? std::sqrt(dp) / std::sqrt(2.0 * e0_ * static_cast<double>(n_)) : 0.0;
    d.log_bytes = log_.bytes() + pre_vals_.size() * sizeof(double) +
                  (pre_keys_.size() + pre_sizes_.size() + wkeys_.size() + 2 * wsizes_.size() + 3 * wmasks_.size()) *
                      sizeof(std::uint64_t);
    d.wall_log_entries = wsizes_.size();
    d.log_pushed = log_.pushed() + log_offset_;
    d.exact_pre_pushed = pre_pushed_;
    d.exact_pre_entries = pre_sizes_.size();
    std::uint64_t parts = 0;
    for (auto c : ncoll_) parts += c;
    d.collisions_per_particle = static_cast<double>(parts) / static_cast<double>(n_);
    d.net_collisions = net_;
    d.counters = counters_;
    return d;
  }

  Snapshot snapshot() const override {
    Snapshot s;
    s.config = cfg_;
    s.n = n_;
    s.time = clock_;
    s.start_time = start_;
    s.net_collisions = net_;
    s.x.resize(n_ * Dim);
    s.v.resize(n_ * Dim);
    s.t_local.resize(n_);
    s.stamp.resize(n_);
    for (std::size_t i = 0; i < n_; ++i) {
      for (int k = 0; k < Dim; ++k) {
        s.x[i * Dim + k] = p_[i].x[k];
        s.v[i * Dim + k] = p_[i].v[k];
      }
      s.t_local[i] = p_[i].t;
      s.stamp[i] = p_[i].stamp;
    }
    s.cell.assign(cell_.begin(), cell_.end());
    s.centre.resize(n_ * Dim);
    for (std::size_t i = 0; i < n_; ++i)
      for (int k = 0; k < Dim; ++k) s.centre[i * Dim + k] = cn_[i].c[k];
    s.ncoll = ncoll_;
    s.rng = rng_;
    s.ev_t.resize(n_);
    s.ev_kind.resize(n_);
    s.ev_partner.resize(n_);
    s.ev_stamp.resize(n_);
    for (std::size_t i = 0; i < n_; ++i) {
      s.ev_t[i] = ev_[i].t;
      s.ev_kind[i] = ev_[i].kind;
      s.ev_partner[i] = ev_[i].partner;
      s.ev_stamp[i] = ev_[i].stamp;
    }
    s.second = second_;
    s.touching.assign(touching_.begin(), touching_.end());
    s.log_cells = log_.cells();
    s.log_pushed = log_.pushed() + log_offset_;
    s.netc = netc_;
    s.wall_keys = wkeys_;
    s.wall_sizes = wsizes_;
    s.wall_masks = wmasks_;
    s.wall_ids = wids_;
    s.wall_netc = wnetc_;
    s.wall_times = wtimes_;
    s.pre_keys = pre_keys_;
    s.pre_sizes = pre_sizes_;
    s.pre_vals = pre_vals_;
    s.pre_pushed = pre_pushed_;
    s.counters = counters_;
    s.energy0 = e0_;
    s.momentum0 = p0_;
    return s;
  }

  std::size_t memory_bytes() const override {
    return n_ * (Dim * (2 * sizeof(double) + sizeof(int)) + sizeof(double) + 3 * sizeof(std::uint64_t) +
                 sizeof(Ev)) +
           head_.size() * sizeof(int) + cn_.size() * sizeof(Centre) + nbn_.size() * sizeof(int) +
           nb_.size() * (sizeof(int) + 1) + queue_.memory_bytes() +
           log_.bytes() + pre_vals_.size() * sizeof(double) +
           (pre_keys_.size() + pre_sizes_.size()) * sizeof(std::uint64_t) + clcg_.size() * sizeof(rng::CLCG4);
  }

 private:
  // ---- geometry, list centres and neighbour lists ----------------------------------------
  // Each particle keeps a list centre c_i (where it was at its last list renewal) and the
  // ids of the particles whose centres lie within D + shell of c_i, each with its periodic
  // image: the lists are symmetric (j on i's iff i on j's) and a pure function of the
  // centres. A particle stays within h = (shell - 1e-3 D) / 2 of its centre: its renewal
  // event fires when it gets there, moves the centre to where it is and rebuilds its list.
  // A pair off each other's lists is therefore more than D (1 + 1e-3) apart (no collision,
  // no contact within group_tol < 1e-3), and a prediction scans ~10 listed particles instead
  // of 27 cells of width D (~25 at 0.45). The cell grid (cells at least D + shell wide)
  // holds the centres and is read by the renewals only.

  // The shell in diameters, from the packing fraction phi. Renewals come about once per
  // h / lambda collisions when the mean free path lambda exceeds the half-shell h and more
  // rarely below it, while a prediction scans ~ phi ((D + shell) / (D / 2))^d listed
  // particles: the best shell grows with lambda. lambda / D is the Enskog estimate,
  // 1 / (6 sqrt2 phi g) in 3D (Carnahan-Starling contact value g), pi / (8 sqrt2 phi g) in 2D
  // (Henderson's g), and the free length per rod (1 - phi) / phi in 1D. The rule's constants
  // fit the sweep in docs/engine.md (Throughput: the shell): the best shell measured was
  // 3D ~1.0 (phi 0.05), 0.6-1.0 (0.1), 0.4-0.8 (0.3), 0.4 (0.45); 2D >= 2.4 (0.05, 0.1),
  // 1.0-1.4 (0.3), 0.8 (0.5); 1D >= 8 (0.1), 4-8 (0.3), 2.4-4 (0.5).
  static double auto_shell(double phi) {
    const double sqrt2 = std::sqrt(2.0);
    double lam, lo, base, slope, hi;
    if constexpr (Dim == 3) {
      const double g = (1.0 - 0.5 * phi) / ((1.0 - phi) * (1.0 - phi) * (1.0 - phi));
      lam = 1.0 / (6.0 * sqrt2 * phi * g);
      lo = 0.4, base = 0.35, slope = 0.3, hi = 1.0;
    } else if constexpr (Dim == 2) {
      const double g = (1.0 - 7.0 * phi / 16.0) / ((1.0 - phi) * (1.0 - phi));
      lam = std::numbers::pi / (8.0 * sqrt2 * phi * g);
      lo = 0.8, base = 0.6, slope = 1.0, hi = 2.5;
    } else {
      lam = (1.0 - phi) / phi;
      lo = 1.5, base = 1.5, slope = 1.0, hi = 10.0;
    }
    return std::isfinite(lam) ? std::clamp(base + slope * lam, lo, hi) : lo;
  }

  void setup_geometry() {
    sigma2_ = cfg_.diameter * cfg_.diameter;
    radius_ = 0.5 * cfg_.diameter;
    contact_tol_ = 2.0 * cfg_.group_tol * sigma2_;
    // listed centres must be within D + shell < L / 2, so that each listed pair has one
    // nearest image: a small periodic box (L >= 3 D) takes a thinner shell
    double vol = 1.0;  // in diameters^d
    for (int k = 0; k < Dim; ++k) vol *= cfg_.box[k] / cfg_.diameter;
    const double phi = static_cast<double>(n_) * particle_volume(Dim, 1.0) / vol;
    shell_ = (cfg_.shell > 0.0 ? cfg_.shell : auto_shell(phi)) * cfg_.diameter;
    for (int k = 0; k < Dim; ++k)
      if (cfg_.boundary[k] == Boundary::periodic)
        shell_ = std::min(shell_, 0.9 * (0.5 * cfg_.box[k] - cfg_.diameter));
    const double reach = cfg_.diameter + shell_;
    list_r2_ = reach * reach;
    renew_h_ = 0.5 * (shell_ - 1e-3 * cfg_.diameter);
    renew_h2_ = renew_h_ * renew_h_;
    total_cells_ = 1;
    for (int k = 0; k < Dim; ++k) {
      L_[k] = cfg_.box[k];
      periodic_[k] = cfg_.boundary[k] == Boundary::periodic;
      nc_[k] = std::max(1, static_cast<int>(std::floor(L_[k] / reach)));
      cw_[k] = L_[k] / nc_[k];
      stride_[k] = total_cells_;
      total_cells_ *= nc_[k];
      shift_tab_[k][0] = 0.0;
      shift_tab_[k][1] = L_[k];
      shift_tab_[k][2] = -L_[k];
      shift_tab_[k][3] = 0.0;
    }
    adj_ = Dim == 1 && (!periodic_[0] || n_ >= 3);
  }

  int cell_of(double x, int k) const {
    int c = static_cast<int>(std::floor(x / cw_[k]));
    return std::clamp(c, 0, nc_[k] - 1);
  }
  int cell_index(std::size_t i) const {
    int c = 0;
    for (int k = 0; k < Dim; ++k) c += cell_[i * Dim + k] * stride_[k];
    return c;
  }
  // i's cell from its centre.
  void place(int i) {
    for (int k = 0; k < Dim; ++k) cell_[i * Dim + k] = cell_of(cn_[i].c[k], k);
  }
  void set_centres(const std::vector<double>& c) {
    cn_.assign(n_, Centre{});
    for (std::size_t i = 0; i < n_; ++i)
      for (int k = 0; k < Dim; ++k) cn_[i].c[k] = c[i * Dim + k];
  }
  void link_all() {
    head_.assign(total_cells_, -1);
    for (std::size_t i = 0; i < n_; ++i) link(static_cast<int>(i));
  }
  void link(int i) {
    const int c = cell_index(i);
    cn_[i].next = head_[c];
    cn_[i].prev = -1;
    if (head_[c] >= 0) cn_[head_[c]].prev = i;
    head_[c] = i;
  }
  void unlink(int i) {
    if (cn_[i].prev >= 0) cn_[cn_[i].prev].next = cn_[i].next;
    else head_[cell_index(i)] = cn_[i].next;
    if (cn_[i].next >= 0) cn_[cn_[i].next].prev = cn_[i].prev;
  }

  // Calls f(j) for every particle j != i whose centre is in the 3^d cells around i's
  // (every cell of a periodic axis with fewer than 3, each once).
  template <class F>
  void for_cells(int i, F&& f) const {
    int idx[3][3];
    int cnt[3] = {1, 1, 1};
    idx[1][0] = idx[2][0] = 0;
    for (int k = 0; k < Dim; ++k) {
      const int c0 = cell_[i * Dim + k];
      cnt[k] = 0;
      if (periodic_[k] && nc_[k] < 3) {
        for (int c = 0; c < nc_[k]; ++c) idx[k][cnt[k]++] = c * stride_[k];
        continue;
      }
      for (int off = -1; off <= 1; ++off) {
        int ck = c0 + off;
        if (ck < 0 || ck >= nc_[k]) {
          if (!periodic_[k]) continue;
          ck += ck < 0 ? nc_[k] : -nc_[k];
        }
        idx[k][cnt[k]++] = ck * stride_[k];
      }
    }
    // the chains are walked side by side, one link of each per round: their loads are
    // independent, so the cache misses overlap (measured faster than one chain at a time)
    int cur[27];
    int m = 0;
    for (int c = 0; c < cnt[2]; ++c)
      for (int b = 0; b < cnt[1]; ++b) {
        const int base = idx[1][b] + idx[2][c];
        for (int a = 0; a < cnt[0]; ++a) {
          const int h = head_[idx[0][a] + base];
          if (h >= 0) cur[m++] = h;
        }
      }
    while (m > 0) {
      int live = 0;
      for (int q = 0; q < m; ++q) {
        const int j = cur[q];
        if (j != i) f(j);
        const int nx = cn_[j].next;
        if (nx >= 0) cur[live++] = nx;
      }
      m = live;
    }
  }

  // Whether j's centre is within D + shell of i's; code: j's nearest image seen from i, 2
  // bits per axis (0: x_j, 1: x_j + L, 2: x_j - L). Symmetric to the bit: near(j, i) gives
  // the same answer and the mirrored code.
  bool near(int i, int j, unsigned& code) const {
    code = 0;
    double d2 = 0.0;
    for (int k = 0; k < Dim; ++k) {
      double d = cn_[i].c[k] - cn_[j].c[k];
      if (periodic_[k]) {
        if (d > 0.5 * L_[k]) {
          d -= L_[k];
          code |= 1u << (2 * k);
        } else if (d < -0.5 * L_[k]) {
          d += L_[k];
          code |= 2u << (2 * k);
        }
      }
      d2 += d * d;
    }
    return d2 < list_r2_;
  }
  static unsigned mirror(unsigned code) { return ((code & 0x15u) << 1) | ((code >> 1) & 0x15u); }
  Vec shift_of(unsigned code) const {
    Vec s;
    for (int k = 0; k < Dim; ++k) s[k] = shift_tab_[k][(code >> (2 * k)) & 3u];
    return s;
  }

  // The lists: nbcap_ slots per particle, ids sorted (a canonical order, the same after a
  // restore), image codes alongside.
  void list_insert(int i, int j, unsigned code) {
    if (nbn_[i] == nbcap_) grow_lists();
    const std::size_t base = static_cast<std::size_t>(i) * nbcap_;
    int m = nbn_[i]++;
    while (m > 0 && nb_[base + m - 1] > j) {
      nb_[base + m] = nb_[base + m - 1];
      nbc_[base + m] = nbc_[base + m - 1];
      --m;
    }
    nb_[base + m] = j;
    nbc_[base + m] = static_cast<unsigned char>(code);
  }
  void list_recode(int i, int j, unsigned code) {
    const std::size_t base = static_cast<std::size_t>(i) * nbcap_;
    int u = 0;
    while (nb_[base + u] != j) ++u;
    nbc_[base + u] = static_cast<unsigned char>(code);
  }
  void list_erase(int i, int j) {
    const std::size_t base = static_cast<std::size_t>(i) * nbcap_;
    const int m = nbn_[i];
    int u = 0;
    while (u < m && nb_[base + u] != j) ++u;
    for (; u + 1 < m; ++u) {
      nb_[base + u] = nb_[base + u + 1];
      nbc_[base + u] = nbc_[base + u + 1];
    }
    --nbn_[i];
  }
  void grow_lists(int least = 0) {
    int cap = 2 * nbcap_;
    while (cap < least) cap *= 2;
    std::vector<int> nb(n_ * cap);
    std::vector<unsigned char> nbc(n_ * cap);
    for (std::size_t i = 0; i < n_; ++i)
      for (int u = 0; u < nbn_[i]; ++u) {
        nb[i * cap + u] = nb_[i * nbcap_ + u];
        nbc[i * cap + u] = nbc_[i * nbcap_ + u];
      }
    nb_.swap(nb);
    nbc_.swap(nbc);
    nbcap_ = cap;
  }
  // Every list from the centres (construction, restore).
  void build_lists() {
    if (adjacent()) {
      build_adjacent();
      return;
    }
    for (std::size_t i = 0; i < n_; ++i) place(static_cast<int>(i));
    link_all();
    nbcap_ = 16;
    nb_.assign(n_ * nbcap_, 0);
    nbc_.assign(n_ * nbcap_, 0);
    nbn_.assign(n_, 0);
    for (std::size_t i = 0; i < n_; ++i)
      for_cells(static_cast<int>(i), [&](int j) {
        unsigned code;
        if (near(static_cast<int>(i), j, code)) list_insert(static_cast<int>(i), j, code);
      });
  }
  // 1D: the rods in order of position (a rotation of the ring's order on a periodic axis,
  // where a stored position lies within kWrap of the box and at most one rod within kWrap
  // of its ends), each listed with the rods beside it.
  static constexpr double kWrap = 0.25;  // in D: a rod is wrapped kWrap D past the box's end
  void build_adjacent() {
    nbcap_ = 2;
    nb_.assign(n_ * nbcap_, 0);
    nbc_.assign(n_ * nbcap_, 0);
    nbn_.assign(n_, 0);
    left_.assign(n_, -1);
    right_.assign(n_, -1);
    std::vector<int> order(n_);
    std::vector<double> x(n_);
    for (std::size_t i = 0; i < n_; ++i) {
      order[i] = static_cast<int>(i);
      x[i] = pos_at(static_cast<int>(i), 0, clock_);
    }
    std::sort(order.begin(), order.end(), [&](int a, int b) { return x[a] < x[b] || (x[a] == x[b] && a < b); });
    const std::size_t pairs = periodic_[0] ? n_ : (n_ > 0 ? n_ - 1 : 0);
    for (std::size_t u = 0; u < pairs; ++u) {
      const int a = order[u], b = order[(u + 1) % n_];  // b is the rod to the right of a
      right_[a] = b;
      left_[b] = a;
      const unsigned code = right_code(a, b);
      list_insert(a, b, code);
      list_insert(b, a, mirror(code));
    }
  }
  // The image of b, the rod to the right of a, seen from a: b itself (code 0) when it lies
  // to the right, else b + L (code 1). Unambiguous: stored positions are within kWrap D < D
  // of the box, and b lies between D and L - 2 D to the right of a on the ring.
  unsigned right_code(int a, int b) const {
    if (!periodic_[0]) return 0u;
    return pos_at(b, 0, clock_) > pos_at(a, 0, clock_) ? 0u : 1u;
  }

  // i's list from its (new) centre, and i on the lists of its old and new neighbours: a
  // merge of the old and new sorted lists, so that only the lists whose entry for i changes
  // are touched (most neighbours stay, and keep their image unless i was wrapped).
  void rebuild_list(int i) {
    int fresh[kMaxList];
    unsigned char fcode[kMaxList];
    int nf = 0;
    bool spill = false;
    for_cells(i, [&](int j) {
      unsigned code;
      if (!near(i, j, code)) return;
      if (nf == kMaxList) { spill = true; return; }
      int m = nf++;
      while (m > 0 && fresh[m - 1] > j) {
        fresh[m] = fresh[m - 1];
        fcode[m] = fcode[m - 1];
        --m;
      }
      fresh[m] = j;
      fcode[m] = static_cast<unsigned char>(code);
    });
    if (spill) {  // beyond kMaxList (not reached, see there): the slow way
      for (int u = 0; u < nbn_[i]; ++u) list_erase(nb_[static_cast<std::size_t>(i) * nbcap_ + u], i);
      nbn_[i] = 0;
      for_cells(i, [&](int j) {
        unsigned code;
        if (!near(i, j, code)) return;
        list_insert(i, j, code);
        list_insert(j, i, mirror(code));
      });
      return;
    }
    int u = 0, w = 0;
    const int no = nbn_[i];
    while (u < no || w < nf) {
      const std::size_t base = static_cast<std::size_t>(i) * nbcap_;  // list_insert may grow the lists
      const int jo = u < no ? nb_[base + u] : std::numeric_limits<int>::max();
      const int jn = w < nf ? fresh[w] : std::numeric_limits<int>::max();
      if (jo < jn) {
        list_erase(jo, i);
        ++u;
      } else if (jn < jo) {
        list_insert(jn, i, mirror(fcode[w]));
        ++w;
      } else {
        if (nbc_[base + u] != fcode[w]) list_recode(jn, i, mirror(fcode[w]));
        ++u;
        ++w;
      }
    }
    if (nf > nbcap_) grow_lists(nf);
    const std::size_t b2 = static_cast<std::size_t>(i) * nbcap_;
    std::copy(fresh, fresh + nf, nb_.begin() + b2);
    std::copy(fcode, fcode + nf, nbc_.begin() + b2);
    nbn_[i] = nf;
  }

  // Calls f(j, shift) for every particle j on i's list; shift is the image offset to add to
  // x_j. This is the engine's inner loop: measure before changing.
  template <class F>
  void for_neighbours(int i, F&& f) const {
    const std::size_t base = static_cast<std::size_t>(i) * nbcap_;
    const int* ids = nb_.data() + base;
    const unsigned char* codes = nbc_.data() + base;
    const int m = nbn_[i];
    // every neighbour's line asked for at once: the scan's branches (approaching or not)
    // are unpredictable, and a mispredicted one would otherwise serialize the misses
    for (int u = 0; u < m; ++u) __builtin_prefetch(&p_[ids[u]]);
    for (int u = 0; u < m; ++u) f(ids[u], shift_of(codes[u]));
  }

  // Image shift s of the pair (a, b), a < b, with r = x_a - x_b - s, from the centres.
  Vec pair_shift(int a, int b) const {
    if (adjacent()) {
      const std::size_t base = static_cast<std::size_t>(a) * nbcap_;
      for (int u = 0; u < nbn_[a]; ++u)
        if (nb_[base + u] == b) return shift_of(nbc_[base + u]);
    }
    unsigned code;
    near(a, b, code);
    return shift_of(code);
  }

  // ---- prediction ---------------------------------------------------------------------

  // Collision time of the pair (a, b), a < b, r = x_a - x_b - s, from the later local time.
  // (Measured: skipping candidates by the lower bound c / (-2 b) before the square root
  // was not faster.)
  bool pair_time(int a, int b, const Vec& s, double& t, bool& touching) const {
    const double ta = p_[a].t, tb = p_[b].t;
    const double tr = ta > tb ? ta : tb;
    const double da = tr - ta, db = tr - tb;
    double r[Dim], w[Dim];
    double bb = 0.0;
    for (int k = 0; k < Dim; ++k) {
      const double va = p_[a].v[k], vb = p_[b].v[k];
      r[k] = ((p_[a].x[k] + va * da) - (p_[b].x[k] + vb * db)) - s[k];
      w[k] = va - vb;
      bb += r[k] * w[k];
    }
    touching = false;
    if (bb > 0.0) return false;  // separating: neither a candidate nor a resting contact
    double r2 = 0.0;
    for (int k = 0; k < Dim; ++k) r2 += r[k] * r[k];
    const double c = r2 - sigma2_;
    touching = c <= contact_tol_;  // in contact, approaching or at rest
    if (!(bb < 0.0)) return false;  // only approaching pairs
    double w2 = 0.0;
    for (int k = 0; k < Dim; ++k) w2 += w[k] * w[k];
    const double disc = bb * bb - w2 * c;
    if (disc < 0.0) return false;
    double dt = c / (-bb + std::sqrt(disc));
    if (dt < 0.0) dt = 0.0;
    t = tr + dt;
    return true;
  }

  // Whether a centre at x touches the wall ahead (upper if up) within group_tol D.
  bool wall_touched(double x, int up, int k) const {
    return (up ? (L_[k] - radius_) - x : x - radius_) <= cfg_.group_tol * cfg_.diameter;
  }

  void predict(int i) {
    Ev best;
    const double ti = p_[i].t;
    for (int k = 0; k < Dim; ++k) {
      const double vk = p_[i].v[k], xk = p_[i].x[k];
      if (vk == 0.0) continue;
      const int up = vk > 0.0 ? 1 : 0;
      bool wall_ok = !periodic_[k];
      if (wall_ok && rev_ && wall_touched(xk + vk * (clock_ - ti), up, k)) {
        // touching and approaching in a reversed run: a flip of a collision's W2 at this
        // instant is undone now; any other touched wall waits for the collision
        const long m = wall_entry(i);
        wall_ok = m >= 0 && (wmasks_[m] >> (8 + k) & 1u);
      }
      if (wall_ok) {
        const double wall = up ? L_[k] - radius_ : radius_;
        double t = ti + (wall - xk) / vk;
        if (t < clock_) t = clock_;
        if (earlier(t, kWall, 2 * k + up, best)) best = Ev{t, kWall, 2 * k + up, 0};
      }
    }
    if (adjacent()) {
      // 1D: no renewal; on a periodic axis the wrap, kWrap D past either end of the box
      const double vk = p_[i].v[0];
      if (periodic_[0] && vk != 0.0) {
        const double edge = vk > 0.0 ? L_[0] + kWrap * cfg_.diameter : -kWrap * cfg_.diameter;
        double t = ti + (edge - p_[i].x[0]) / vk;
        if (t < clock_) t = clock_;
        if (earlier(t, kRenew, 0, best)) best = Ev{t, kRenew, 0, 0};
      }
    } else {
      // the list renewal: |x_i + v (t - t_i) - c_i| = h, the later root, cancellation-free
      double dd = 0.0, b = 0.0, vv = 0.0;
      for (int k = 0; k < Dim; ++k) {
        const double dk = p_[i].x[k] - cn_[i].c[k], vk = p_[i].v[k];
        dd += dk * dk;
        b += dk * vk;
        vv += vk * vk;
      }
      if (vv > 0.0) {
        const double c = renew_h2_ - dd;  // > 0: x_i inside the sphere
        const double disc = b * b + vv * c;
        double tau = 0.0;  // outside and not entering: round-off at the surface, renew now
        if (disc > 0.0) tau = b <= 0.0 ? (-b + std::sqrt(disc)) / vv : c / (b + std::sqrt(disc));
        double t = ti + tau;
        if (t < clock_) t = clock_;
        if (earlier(t, kRenew, 0, best)) best = Ev{t, kRenew, 0, 0};
      }
    }
    double first = kInf, second = kInf;  // the two earliest collision times (the group gate)
    bool touch = false;
    for_neighbours(i, [&](int j, const Vec& sh) {
      double t;
      bool hit, tj = false;
      if (i < j) {
        hit = pair_time(i, j, sh, t, tj);
      } else {
        Vec s;
        for (int k = 0; k < Dim; ++k) s[k] = -sh[k];
        hit = pair_time(j, i, s, t, tj);
      }
      if (tj) {
        touch = true;
        touching_[j] = 1;
      }
      if (!hit) return;
      if (t < clock_) t = clock_;
      if (t < first) {
        second = first;
        first = t;
      } else if (t < second) {
        second = t;
      }
      if (earlier(t, kColl, j, best)) best = Ev{t, kColl, j, p_[j].stamp};
    });
    ev_[i] = best;
    second_[i] = second;
    touching_[i] = touch ? 1 : 0;
  }

  // ---- the event queue (revcol/engine/event_queue.hpp), key (t, kind, id) ----------------

  // Every event into the queue (construction, restore, reversal): the window starts at the
  // clock, ~8 events per bucket from the median distance of the events ahead.
  void build_heap() {
    std::vector<double> ahead;
    ahead.reserve(n_);
    for (std::size_t i = 0; i < n_; ++i)
      if (ev_[i].t < kInf) ahead.push_back(ev_[i].t - clock_);
    double width = 0.0;
    if (!ahead.empty()) {
      auto mid = ahead.begin() + ahead.size() / 2;
      std::nth_element(ahead.begin(), mid, ahead.end());
      width = 8.0 * 2.0 * *mid / static_cast<double>(ahead.size());
    }
    if (!(width > 0.0) || !std::isfinite(width)) width = 1.0;
    queue_.reset(n_, clock_, width);
    for (std::size_t i = 0; i < n_; ++i) update(static_cast<int>(i));
  }
  void update(int i) { queue_.set(i, ev_[i].t, ev_[i].kind); }
  void rebuild_events() {
    for (std::size_t i = 0; i < n_; ++i) predict(static_cast<int>(i));
    build_heap();
  }
  void repredict(int i) {
    predict(i);
    update(i);
  }

  // ---- state changes ------------------------------------------------------------------

  void advance(int i, double t) {
    const double dt = t - p_[i].t;
    for (int k = 0; k < Dim; ++k) p_[i].x[k] += p_[i].v[k] * dt;
    p_[i].t = t;
    ++p_[i].stamp;
  }

  // Negates velocities, local times and the clock; rebuilds every prediction.
  void flip() {
    for (auto& q : p_) {
      for (int k = 0; k < Dim; ++k) q.v[k] = -q.v[k];
      q.t = -q.t;
    }
    clock_ = -clock_;
    rev_ = !rev_;
    for (auto& q : p_) ++q.stamp;
    rebuild_events();
  }

  void wall_event(int i, const Ev& e) {
    advance(i, e.t);
    if (rev_) {
      // arriving at a wall at the instant of a logged collision: only W2's flips are
      // undone here; a wall that collision left untouched waits for it
      const long m = wall_entry(i);
      if (m >= 0) {
        const std::uint64_t bit = 1ull << (8 + e.partner / 2);
        if (!(wmasks_[m] & bit)) {
          repredict(i);
          return;
        }
        wmasks_[m] &= ~bit;
      }
    }
    const int k = e.partner / 2;
    p_[i].v[k] = -p_[i].v[k];
    ++counters_.wall_events;
    repredict(i);
  }

  // The list renewal: the centre moves to where i is now (wrapped into the box on periodic
  // axes, moving the stored position by L: its line, and so every prediction, is unchanged),
  // i's list is rebuilt (in 1D, the images of the rods beside it recoded: this is then the
  // wrap) and i is predicted again. Nothing physical changes: no stamp.
  void renew_event(int i, const Ev& e) {
    move_centre(i, e.t);
    if (adjacent()) {
      recode_beside(i);
    } else {
      unlink(i);  // from the cell it was linked in (cell_ still holds it)
      place(i);
      link(i);
      rebuild_list(i);
    }
    ++counters_.cell_crossings;
    repredict(i);
  }

  // i's centre to where i is at t; on a periodic axis a position outside the box is first
  // moved by L (its line, and so every prediction, is unchanged).
  void move_centre(int i, double t) {
    const double dt = t - p_[i].t;
    for (int k = 0; k < Dim; ++k) {
      double c = p_[i].x[k] + p_[i].v[k] * dt;
      if (periodic_[k] && (c >= L_[k] || c < 0.0)) {
        p_[i].x[k] += c < 0.0 ? L_[k] : -L_[k];
        c = p_[i].x[k] + p_[i].v[k] * dt;
      }
      cn_[i].c[k] = c;
    }
  }

  // 1D periodic: i has gone kWrap D past an end of the box and been moved by L: the images
  // of its pairs with the rods beside it are recoded.
  void recode_beside(int i) {
    const int r = right_[i], l = left_[i];
    const unsigned cr = right_code(i, r), cl = right_code(l, i);
    list_recode(i, r, cr);
    list_recode(r, i, mirror(cr));
    list_recode(l, i, cl);
    list_recode(i, l, mirror(cl));
  }

  // ---- random numbers -----------------------------------------------------------------

  std::size_t stream_count() const { return cfg_.streams == rng::StreamPolicy::single ? 1 : n_; }

  // The stream a collision whose smallest particle id is `id` draws from.
  int stream_of(int id) const { return cfg_.streams == rng::StreamPolicy::single ? 0 : id; }

  // CLCG4 only: each stream's state, from the family and the draws taken (rng_).
  void make_generators() {
    clcg_.clear();
    if (cfg_.generator != Generator::clcg4) return;
    clcg_ = rng::generator_traits<rng::CLCG4>::family(cfg_.seed, stream_count());
    for (std::size_t i = 0; i < clcg_.size(); ++i) {
      if (rng_[i] == 0) continue;
      rng::CLCG4::State st = clcg_[i].state();
      for (int j = 0; j < 4; ++j)
        st[j] = rng::clcg4_detail::mulmod(
            st[j], rng::clcg4_detail::powmod(rng::CLCG4::multiplier[j], rng_[i], rng::CLCG4::modulus[j]),
            rng::CLCG4::modulus[j]);
      clcg_[i].set_state(st);
    }
  }

  double draw(int stream, bool reversed) {
    if (cfg_.generator == Generator::clcg4) {
      if (reversed) {
        --rng_[stream];
        return clcg_[stream].prev();
      }
      ++rng_[stream];
      return clcg_[stream].next();
    }
    const rng::Philox p({static_cast<std::uint32_t>(stream), cfg_.seed}, 0);
    if (reversed) return p.at(--rng_[stream]);
    return p.at(rng_[stream]++);
  }

  // Members of the contact component of (a, b) at time t, each with its image offset.
  struct Group {
    int n = 0;
    int id[kMaxGroup];
    Vec off[kMaxGroup];
    int ne = 0;
    int ea[3 * kMaxGroup], eb[3 * kMaxGroup];  // edges as member indices, ids ea < eb by id
    bool overflow = false;
  };

  double pos_at(int j, int k, double t) const { return p_[j].x[k] + p_[j].v[k] * (t - p_[j].t); }

  void gather(int a, int b, const Vec& s, double t, Group& g) const {
    g.n = 2;
    g.id[0] = a;
    g.off[0] = Vec{};
    g.id[1] = b;
    g.off[1] = s;  // x_b + s is b's image next to a
    g.ne = 1;
    g.ea[0] = 0;
    g.eb[0] = 1;
    for (int m = 0; m < g.n && !g.overflow; ++m) {
      const int im = g.id[m];
      Vec pm;
      for (int k = 0; k < Dim; ++k) pm[k] = pos_at(im, k, t);
      for_neighbours(im, [&](int j, const Vec& sh) {
        if (g.overflow) return;
        double r2 = 0.0, rw = 0.0;
        double r[Dim];
        for (int k = 0; k < Dim; ++k) {
          r[k] = pm[k] - (pos_at(j, k, t) + sh[k]);
          r2 += r[k] * r[k];
        }
        if (!(r2 - sigma2_ <= contact_tol_)) return;
        for (int k = 0; k < Dim; ++k) rw += r[k] * (p_[im].v[k] - p_[j].v[k]);
        if (!(rw <= 0.0)) return;
        int q = -1;
        for (int u = 0; u < g.n; ++u)
          if (g.id[u] == j) q = u;
        if (q < 0) {
          if (g.n == kMaxGroup) { g.overflow = true; return; }
          q = g.n++;
          g.id[q] = j;
          for (int k = 0; k < Dim; ++k) g.off[q][k] = g.off[m][k] + sh[k];
        } else {
          // the same image? (a component wrapping around the box is not one contact set)
          for (int k = 0; k < Dim; ++k)
            if (g.off[q][k] != g.off[m][k] + sh[k]) return;
        }
        for (int e = 0; e < g.ne; ++e)
          if ((g.ea[e] == m && g.eb[e] == q) || (g.ea[e] == q && g.eb[e] == m)) return;
        if (g.ne == 3 * kMaxGroup) { g.overflow = true; return; }
        g.ea[g.ne] = m;
        g.eb[g.ne] = q;
        ++g.ne;
      });
    }
  }

  // ---- walls at a collision's instant --------------------------------------------------
  // A particle of a collision that touches a wall (within group_tol D) and approaches it is
  // reflected before the collision operator (W1), and again after it if the operator sends
  // it into a touched wall (W2): walls, particles, walls. Which components W1 and W2 flipped
  // cannot be read off the post state (a touched wall left after the collision looks the
  // same as one left after a reflection: the wall operator's two-to-one case), so the
  // forward run keeps the flip masks, keyed by (smallest id, that particle's net collision
  // count), only for collisions with a wall flip (none in a gas but at corners and
  // walls hit at the same instant). The reversed collision undoes W2, reverses the
  // operator, undoes W1. A reversed run schedules no standalone wall event for a particle
  // that touches the wall already (those flips belong to a collision's masks).

  unsigned touch_walls(int i) {
    const double tol = cfg_.group_tol * cfg_.diameter;
    unsigned mask = 0;
    for (int k = 0; k < Dim; ++k) {
      if (periodic_[k]) continue;
      double& vk = p_[i].v[k];
      const double xk = p_[i].x[k];
      if ((vk < 0.0 && xk - radius_ <= tol) || (vk > 0.0 && (L_[k] - radius_) - xk <= tol)) {
        vk = -vk;
        mask |= 1u << k;
        ++counters_.wall_events;
      }
    }
    return mask;
  }
  void flip_mask(int i, unsigned mask) {
    for (int k = 0; k < Dim; ++k)
      if (mask >> k & 1u) {
        p_[i].v[k] = -p_[i].v[k];
        ++counters_.wall_events;
      }
  }
  bool touches_wall(int i) const {
    const double tol = cfg_.group_tol * cfg_.diameter;
    for (int k = 0; k < Dim; ++k)
      if (!periodic_[k] && (p_[i].x[k] - radius_ <= tol || (L_[k] - radius_) - p_[i].x[k] <= tol)) return true;
    return false;
  }
  // Forward: keeps the masks of a collision at a wall, with its members, their net
  // collision counts and its time (ids in the collision's order).
  void push_walls(int id, std::int64_t key, double t, int n, const int* ids, const unsigned* w1,
                  const unsigned* w2) {
    wkeys_.push_back(static_cast<std::uint64_t>(id));
    wkeys_.push_back(static_cast<std::uint64_t>(key));
    wtimes_.push_back(t);
    wsizes_.push_back(static_cast<std::uint64_t>(n));
    for (int u = 0; u < n; ++u) {
      wids_.push_back(static_cast<std::uint64_t>(ids[u]));
      wnetc_.push_back(netc_[ids[u]]);
      wmasks_.push_back(w1[u] | (w2[u] << 8));
    }
  }
  // Reverse: the masks of the collision keyed (id, key), popped, or zeros.
  void pop_walls(int id, std::int64_t key, int n, unsigned* w1, unsigned* w2) {
    for (int u = 0; u < n; ++u) w1[u] = w2[u] = 0;
    if (wsizes_.empty()) return;
    const std::size_t e = wsizes_.size() - 1;
    if (wkeys_[2 * e] != static_cast<std::uint64_t>(id) || wkeys_[2 * e + 1] != static_cast<std::uint64_t>(key) ||
        wsizes_[e] != static_cast<std::uint64_t>(n))
      return;
    const std::size_t at = wmasks_.size() - n;
    for (int u = 0; u < n; ++u) {
      w1[u] = static_cast<unsigned>(wmasks_[at + u] & 0xffu);
      w2[u] = static_cast<unsigned>(wmasks_[at + u] >> 8);
    }
    wmasks_.resize(at);
    wids_.resize(at);
    wnetc_.resize(at);
    wsizes_.pop_back();
    wtimes_.pop_back();
    wkeys_.resize(wkeys_.size() - 2);
  }
  // Reverse: the member slot of i in the wall-log entry of i's next reversed collision if
  // that collision is at the current instant, else -1. (The log is short: at most 64
  // entries are searched.)
  long wall_entry(int i) const {
    if (wsizes_.empty()) return -1;
    const double tnow = rev_ ? -clock_ : clock_;
    std::size_t off = wmasks_.size();
    std::size_t e = wsizes_.size();
    for (int seen = 0; e > 0 && seen < 64; ++seen) {
      --e;
      off -= wsizes_[e];
      for (std::size_t u = off; u < off + wsizes_[e]; ++u) {
        if (wids_[u] != static_cast<std::uint64_t>(i)) continue;
        if (wnetc_[u] != netc_[i] - 1) return -1;
        return std::fabs(wtimes_[e] - tnow) <= 1e-9 * (std::fabs(tnow) + 1.0) ? static_cast<long>(u) : -1;
      }
    }
    return -1;
  }

  void finish_collision(int i, bool reversed) {
    ++ncoll_[i];
    ++p_[i].stamp;
    netc_[i] += reversed ? -1 : 1;
  }

  // A collision of a and b predicted at t (stamps checked). Returns whether one happened.
  bool collide(int a, int b, double t, bool reversed) {
    if (a > b) std::swap(a, b);
    const Vec s = pair_shift(a, b);
    // The gather scans two neighbourhoods; it runs only when a group is possible: a
    // neighbour was within the contact tolerance at a prediction (resting contacts), or a
    // second collision of a or b was predicted within a relative 1e-9 of t (ties).
    const double window = t + 1e-9 * (std::fabs(t) + 1.0);
    const bool maybe = cfg_.force_group_search || touching_[a] || touching_[b] || second_[a] <= window ||
                       second_[b] <= window;
    if (cfg_.groups && maybe) {
      Group g;
      gather(a, b, s, t, g);
      if (g.n > 2 || g.overflow) {
        if (!g.overflow && group_collide(g, t, reversed)) return true;
        ++counters_.group_fallbacks;
      }
    }
    advance(a, t);
    advance(b, t);
    const std::int64_t wkey = reversed ? netc_[a] - 1 : netc_[a];
    unsigned w1[2] = {0, 0}, w2[2] = {0, 0};
    if (reversed) {
      pop_walls(a, wkey, 2, w1, w2);
      flip_mask(a, w2[0]);
      flip_mask(b, w2[1]);
    } else {
      w1[0] = touch_walls(a);
      w1[1] = touch_walls(b);
    }
    std::array<double, Dim> r;
    double rw = 0.0;
    for (int k = 0; k < Dim; ++k) {
      r[k] = (p_[a].x[k] - p_[b].x[k]) - s[k];
      rw += r[k] * (p_[a].v[k] - p_[b].v[k]);
    }
    if (!(rw < 0.0)) {  // grazing: round-off left no approach at contact
      ++counters_.grazing_skipped;
      repredict(a);
      repredict(b);
      return false;
    }
    PairV<Dim> in;
    for (int k = 0; k < Dim; ++k) {
      in.i[k] = p_[a].v[k];
      in.j[k] = p_[b].v[k];
    }
    PairV<Dim> out;
    try {
      out = apply_pair(in, r, stream_of(a), reversed);
    } catch (const InvalidArgument&) {
      // Only a reversed run can get here: a post state this operator cannot reverse (the
      // rare log is empty, or the state fails validation) means the reversed trajectory has
      // left the forward one (beyond the round-off horizon). The pair reflects specularly,
      // drawing nothing, and the failure is counted: the restored state is not the start.
      if (!reversed) throw;
      ++counters_.reverse_failures;
      out = specular(in, r);
    }
    for (int k = 0; k < Dim; ++k) {
      p_[a].v[k] = out.i[k];
      p_[b].v[k] = out.j[k];
    }
    if (reversed) {
      flip_mask(a, w1[0]);
      flip_mask(b, w1[1]);
    } else {
      w2[0] = touch_walls(a);
      w2[1] = touch_walls(b);
      if (w1[0] | w1[1] | w2[0] | w2[1] || touches_wall(a) || touches_wall(b)) {
        const int ids[2] = {a, b};
        push_walls(a, wkey, t, 2, ids, w1, w2);
      }
    }
    finish_collision(a, reversed);
    finish_collision(b, reversed);
    ++counters_.pair_collisions;
    repredict(a);
    repredict(b);
    return true;
  }

  // forward: op.forward(v); reversed (velocities negated): -op.reverse(-v), draws stepped back.
  PairV<Dim> apply_pair(const PairV<Dim>& in, const std::array<double, Dim>& r, int stream, bool reversed) {
    if constexpr (Dim == 1) {
      (void)stream;
      (void)reversed;
      return Pair1D{}.forward(in, r[0]);  // exchange: its own inverse, and -swap(-v) = swap(v)
    } else {
      PairV<Dim> arg = in;
      if (reversed)
        for (int k = 0; k < Dim; ++k) {
          arg.i[k] = -arg.i[k];
          arg.j[k] = -arg.j[k];
        }
      PairV<Dim> out;
      if constexpr (Dim == 2) {
        const double g = draw(stream, reversed);
        if (cfg_.mode == Mode::paper)
          out = reversed ? p2p_.reverse(arg, r, g, log_) : p2p_.forward(arg, r, g, log_);
        else
          out = reversed ? p2e_.reverse(arg, r, g, log_) : p2e_.forward(arg, r, g, log_);
      } else {
        std::array<double, 2> g;
        if (reversed) {
          g[1] = draw(stream, true);
          g[0] = draw(stream, true);
        } else {
          g[0] = draw(stream, false);
          g[1] = draw(stream, false);
        }
        const std::uint64_t key = rng_[stream];  // forward: before the draws; reverse: after stepping back
        if (reversed) {
          out = p3_.reverse(arg, r, g, log_);
          pop_exact_pre(stream, key, out.i.data(), out.j.data());
        } else {
          out = p3_.forward(arg, r, g, log_);
          // near head-on (eta < ~1e-2) the pre cell of the polar chart is wide: keep the
          // pre state when its cell centre is off by more than 1e-10 (rare in a gas)
          double w2 = 0.0, rr = 0.0, rw = 0.0;
          for (int k = 0; k < 3; ++k) {
            const double w = arg.i[k] - arg.j[k];
            w2 += w * w;
            rr += r[k] * r[k];
            rw += r[k] * w;
          }
          if (w2 * rr - rw * rw < 1e-4 * w2 * rr) {
            const PairV<3> q = p3_.quantize(arg, r);
            if (off_by(arg.i.data(), q.i.data(), 3) || off_by(arg.j.data(), q.j.data(), 3))
              push_exact_pre(stream, key - 2, arg.i.data(), arg.j.data(), 3);
          }
        }
      }
      if (reversed)
        for (int k = 0; k < Dim; ++k) {
          out.i[k] = -out.i[k];
          out.j[k] = -out.j[k];
        }
      return out;
    }
  }

  static PairV<Dim> specular(const PairV<Dim>& in, const std::array<double, Dim>& r) {
    double rr = 0.0, rw = 0.0;
    for (int k = 0; k < Dim; ++k) {
      rr += r[k] * r[k];
      rw += r[k] * (in.i[k] - in.j[k]);
    }
    const double f = rw / rr;
    PairV<Dim> out = in;
    for (int k = 0; k < Dim; ++k) {
      out.i[k] -= f * r[k];
      out.j[k] += f * r[k];
    }
    return out;
  }

  // ---- the exact-pre log --------------------------------------------------------------
  // Pre states that their chart cell cannot give back to 1e-10 (singular points of the
  // chart: head-on 3D pairs, resting contacts in groups) are kept whole, keyed by (stream,
  // generator counter before the collision's draws), which names the collision uniquely;
  // the reversed collision pops the entry when the key on top matches. Empty in a gas
  // almost always (diagnostics: log_bytes counts it with the rare log).

  static bool off_by(const double* a, const double* b, int n) {
    double amax = 0.0, d = 0.0;
    for (int k = 0; k < n; ++k) {
      amax = std::fmax(amax, std::fabs(a[k]));
      d = std::fmax(d, std::fabs(a[k] - b[k]));
    }
    return d > 1e-10 * amax;
  }
  void push_exact_pre(int stream, std::uint64_t key, const double* a, const double* b, int n) {
    pre_keys_.push_back(static_cast<std::uint64_t>(stream));
    pre_keys_.push_back(key);
    pre_sizes_.push_back(static_cast<std::uint64_t>(b ? 2 * n : n));
    pre_vals_.insert(pre_vals_.end(), a, a + n);
    if (b) pre_vals_.insert(pre_vals_.end(), b, b + n);
    ++pre_pushed_;
  }
  // In the forward frame: a (and b, the second half of a pair) are the pre velocities the
  // reverse computed; replaced by the kept ones when the top entry is this collision's.
  void pop_exact_pre(int stream, std::uint64_t key, double* a, double* b) {
    if (pre_sizes_.empty()) return;
    const std::size_t e = pre_sizes_.size() - 1;
    if (pre_keys_[2 * e] != static_cast<std::uint64_t>(stream) || pre_keys_[2 * e + 1] != key) return;
    const std::size_t n = pre_sizes_[e];
    const double* src = pre_vals_.data() + (pre_vals_.size() - n);
    if (b) {
      std::copy(src, src + n / 2, a);
      std::copy(src + n / 2, src + n, b);
    } else {
      std::copy(src, src + n, a);
    }
    pre_vals_.resize(pre_vals_.size() - n);
    pre_sizes_.pop_back();
    pre_keys_.resize(pre_keys_.size() - 2);
  }

  bool group_collide(Group& g, double t, bool reversed) {
    // members sorted by id; edges re-indexed, oriented from the larger id to the smaller
    int order[kMaxGroup];
    for (int u = 0; u < g.n; ++u) order[u] = u;
    for (int u = 1; u < g.n; ++u)  // insertion sort by id (n <= 8)
      for (int w = u; w > 0 && g.id[order[w]] < g.id[order[w - 1]]; --w) std::swap(order[w], order[w - 1]);
    int rank[kMaxGroup];
    for (int u = 0; u < g.n; ++u) rank[order[u]] = u;
    struct E {
      int i, j, mi, mj;
    };
    std::vector<E> edges;
    edges.reserve(g.ne);
    for (int e = 0; e < g.ne; ++e) {
      int p = g.ea[e], q = g.eb[e];
      if (g.id[p] > g.id[q]) std::swap(p, q);
      edges.push_back({rank[p], rank[q], p, q});
    }
    std::sort(edges.begin(), edges.end(), [](const E& x, const E& y) { return x.i != y.i ? x.i < y.i : x.j < y.j; });
    const int n = g.n;
    std::vector<Contact> contacts;
    std::vector<double> normals;
    for (const E& e : edges) {
      contacts.push_back({e.i, e.j});
      for (int k = 0; k < Dim; ++k) {
        const double xi = pos_at(g.id[e.mi], k, t) + g.off[e.mi][k];
        const double xj = pos_at(g.id[e.mj], k, t) + g.off[e.mj][k];
        normals.push_back(xi - xj);
      }
    }
    const int first = g.id[order[0]];
    const std::int64_t wkey = reversed ? netc_[first] - 1 : netc_[first];
    unsigned w1[kMaxGroup], w2[kMaxGroup];
    for (int u = 0; u < n; ++u) advance(g.id[order[u]], t);
    if (reversed) {
      pop_walls(first, wkey, n, w1, w2);
      for (int u = 0; u < n; ++u) flip_mask(g.id[order[u]], w2[u]);
    } else {
      for (int u = 0; u < n; ++u) w1[u] = touch_walls(g.id[order[u]]);
    }
    std::vector<double> pre(n * Dim), post(n * Dim);
    for (int u = 0; u < n; ++u)
      for (int k = 0; k < Dim; ++k) {
        const double vk = p_[g.id[order[u]]].v[k];
        pre[u * Dim + k] = reversed ? -vk : vk;
      }
    const int stream = stream_of(g.id[order[0]]);
    try {
      const ExactCollision op(n, Dim, contacts, normals, cfg_.law, cfg_.bits);
      const int m = op.draws();
      std::vector<double> gs(m);
      if (reversed) {
        op.check_post(pre.data());
        for (int k = m - 1; k >= 0; --k) gs[k] = draw(stream, true);
        op.reverse(pre.data(), gs.data(), post.data(), log_);
        pop_exact_pre(stream, rng_[stream], post.data(), nullptr);
      } else {
        op.check_pre(pre.data());
        const std::uint64_t key = rng_[stream];
        for (int k = 0; k < m; ++k) gs[k] = draw(stream, false);
        op.forward(pre.data(), gs.data(), post.data(), log_);
        // resting contacts and aligned velocities put the pre state on a singular set of
        // the chart (a vertex of T, eta = 0), where its cell spans ~2^-K/2: keep it exactly
        std::vector<double> q(n * Dim);
        op.quantize(pre.data(), q.data());
        if (off_by(pre.data(), q.data(), n * Dim)) push_exact_pre(stream, key, pre.data(), nullptr, n * Dim);
      }
    } catch (const InvalidArgument&) {
      // refused before any draw was consumed (validation comes first): undo the walls
      for (int u = 0; u < n; ++u) flip_mask(g.id[order[u]], reversed ? w2[u] : w1[u]);
      if (reversed) {
        for (int u = 0; u < n; ++u) w1[u] |= w2[u] << 8;
        if (std::any_of(w1, w1 + n, [](unsigned q) { return q != 0; })) {
          int ids[kMaxGroup];
          for (int u = 0; u < n; ++u) {
            w2[u] = w1[u] >> 8;
            w1[u] &= 0xffu;
            ids[u] = g.id[order[u]];
          }
          push_walls(first, wkey, t, n, ids, w1, w2);  // put the masks back
        }
      }
      return false;
    }
    for (int u = 0; u < n; ++u) {
      const int id = g.id[order[u]];
      for (int k = 0; k < Dim; ++k) p_[id].v[k] = reversed ? -post[u * Dim + k] : post[u * Dim + k];
      if (reversed) flip_mask(id, w1[u]);
      else w2[u] = touch_walls(id);
      finish_collision(id, reversed);
    }
    if (!reversed) {
      int ids[kMaxGroup];
      bool any = false;
      for (int u = 0; u < n; ++u) {
        ids[u] = g.id[order[u]];
        any = any || w1[u] != 0 || w2[u] != 0 || touches_wall(ids[u]);
      }
      if (any) {
        // the keys must be the counts before this collision: undo finish_collision's step
        for (int u = 0; u < n; ++u) --netc_[ids[u]];
        push_walls(first, wkey, t, n, ids, w1, w2);
        for (int u = 0; u < n; ++u) ++netc_[ids[u]];
      }
    }
    ++counters_.group_collisions;
    counters_.group_particles += static_cast<std::uint64_t>(n);
    for (int u = 0; u < n; ++u) repredict(g.id[u]);
    return true;
  }

  // ---- the event loop -----------------------------------------------------------------

  RunResult loop(std::uint64_t max_collisions, double t_end, const Progress& cb, std::uint64_t every,
                 bool reversed) {
    RunResult res;
    double t_last = clock_;
    bool done_count = max_collisions == 0;
    while (true) {
      const int i = queue_.top();
      if (i < 0) break;  // nothing scheduled (never: every particle has an event, maybe at infinity)
      const Ev e = ev_[i];
      if (done_count) {
        // finish the instant of the last collision, then stop half way to the next event
        if (e.t > t_last || e.t == kInf) {
          double te = e.t == kInf ? t_last : t_last + 0.5 * (e.t - t_last);
          if (te > t_end) te = t_end;
          if (te > clock_) clock_ = te;
          break;
        }
      } else if (e.t > t_end || e.t == kInf) {
        if (t_end != kInf && t_end > clock_) clock_ = t_end;
        break;
      }
      clock_ = e.t;
      ++res.events;
      ++counters_.events;
      if (e.kind == kWall) {
        wall_event(i, e);
      } else if (e.kind == kRenew) {
        renew_event(i, e);
      } else if (e.kind == kColl) {
        if (p_[e.partner].stamp != e.stamp) {
          ++counters_.invalid_events;
          repredict(i);
          continue;
        }
        if (collide(i, e.partner, e.t, reversed)) {
          ++res.collisions;
          if (reversed) {
            --net_;
            ++counters_.reverse_collisions;
          } else {
            ++net_;
            ++counters_.forward_collisions;
          }
          t_last = e.t;
          if (res.collisions >= max_collisions) done_count = true;
          if (cb && every > 0 && res.collisions % every == 0 && !cb(res.collisions)) {
            res.interrupted = true;
            done_count = true;
          }
        }
      } else {
        break;
      }
    }
    res.time = clock_;
    return res;
  }

  Config cfg_;
  std::size_t n_;
  std::array<double, Dim> L_{}, cw_{};
  std::array<int, Dim> nc_{}, stride_{};
  std::array<bool, Dim> periodic_{};
  int total_cells_ = 1;
  double sigma2_ = 1.0, radius_ = 0.5, contact_tol_ = 0.0;
  double shell_ = 0.0, list_r2_ = 0.0, renew_h_ = 0.0, renew_h2_ = 0.0;  // the neighbour lists
  double shift_tab_[Dim][4] = {};                                           // image code -> shift

  // One particle's stored state, one cache line in 3D: the neighbour scan reads it whole.
  struct alignas(Dim == 3 ? 64 : 8) Particle {
    double x[Dim] = {};    // position at local time t
    double v[Dim] = {};    // velocity
    double t = 0.0;        // local time
    std::uint64_t stamp = 0;  // changes whenever x, v or t change (event invalidation)
  };
  std::vector<Particle> p_;
  std::vector<int> cell_, head_;  // cells of the list centres, heads of their chains
  // A list centre with the links of its cell's chain: the renewal's scan reads one line each.
  struct alignas(Dim == 3 ? 32 : 8) Centre {
    double c[Dim] = {};
    int next = -1, prev = -1;
  };
  std::vector<Centre> cn_;
  // 1D (walls, or a periodic ring of 3 or more): rods keep their order, so each one's
  // neighbours are the rods beside it for the whole run: no cell grid and no list renewals,
  // only a wrap event on a periodic axis (adj_; left_/right_: the rods beside, -1 at a wall)
  bool adj_ = false;
  bool adjacent() const { return Dim == 1 && adj_; }  // a constant false in 2D and 3D
  std::vector<int> left_, right_;
  std::vector<int> nb_, nbn_;                        // neighbour lists (nbcap_ slots each), lengths
  std::vector<unsigned char> nbc_;                   // their image codes
  int nbcap_ = 16;
  EventQueue<double> queue_;                   // one event per particle, key (t, kind, id)
  std::vector<std::uint64_t> ncoll_, rng_;  // rng_: draws taken, per stream
  std::vector<rng::CLCG4> clcg_;             // CLCG4 only: one generator per stream
  std::vector<Ev> ev_;
  mutable std::vector<double> second_;           // second earliest collision time per particle
  mutable std::vector<unsigned char> touching_;  // a neighbour within the contact tolerance
  double clock_ = 0.0, start_ = 0.0;
  std::int64_t net_ = 0;
  RareLog log_;
  std::uint64_t log_offset_ = 0;
  std::vector<std::uint64_t> pre_keys_, pre_sizes_;  // the exact-pre log: (stream, key), sizes
  std::vector<double> pre_vals_;                       // and the kept velocities
  std::uint64_t pre_pushed_ = 0;
  std::vector<std::uint64_t> wkeys_, wsizes_, wmasks_, wids_;  // the wall-mask log (see touch_walls)
  std::vector<std::int64_t> wnetc_;
  std::vector<double> wtimes_;
  std::vector<std::int64_t> netc_;                       // net collisions per particle
  bool rev_ = false;                                     // inside a reversed run
  Counters counters_;
  double e0_ = 0.0;
  std::array<double, 3> p0_{};

  Pair2DExact p2e_;
  Pair2DPaper p2p_;
  EnginePair3D p3_;
};

// Cold validation of a state (nothing built yet).
void validate_state(const Config& c, const std::vector<double>& x, const std::vector<double>& v) {
  validate_config(c);
  const int d = c.dim;
  require(!x.empty(), "no particles (N = 0)");
  require(x.size() % d == 0, "positions must have n x dim entries");
  require(v.size() == x.size(), "velocities must have the same shape as positions");
  const std::size_t n = x.size() / d;
  require(n < (std::size_t{1} << 31), "too many particles (N must be < 2^31)");
  const double r = 0.5 * c.diameter;
  double e = 0.0;
  for (std::size_t i = 0; i < n; ++i)
    for (int k = 0; k < d; ++k) {
      const double xk = x[i * d + k], vk = v[i * d + k];
      require(std::isfinite(xk), [&] { return "position of particle " + std::to_string(i) + " is not finite"; });
      require(std::isfinite(vk), [&] { return "velocity of particle " + std::to_string(i) + " is not finite"; });
      if (c.boundary[k] == Boundary::wall)
        require(xk >= r && xk <= c.box[k] - r, [&] {
          return "particle " + std::to_string(i) + " is outside the box on axis " + std::to_string(k) + ": x = " +
                 std::to_string(xk) + ", allowed [" + std::to_string(r) + ", " + std::to_string(c.box[k] - r) +
                 "] (walls at 0 and L, centre at least D/2 inside)";
        });
      else
        require(xk >= 0.0 && xk < c.box[k], [&] {
          return "particle " + std::to_string(i) + " is outside the periodic box on axis " + std::to_string(k) +
                 ": x = " + std::to_string(xk) + ", allowed [0, " + std::to_string(c.box[k]) + ")";
        });
      e += 0.5 * vk * vk;
    }
  require(std::isfinite(e), "kinetic energy overflows");
  require(e > 0.0, "zero kinetic energy: nothing would ever move");
  // overlaps through a cell grid (cells >= D)
  std::array<int, 3> nc{1, 1, 1};
  std::array<double, 3> cw{1, 1, 1};
  std::size_t total = 1;
  for (int k = 0; k < d; ++k) {
    nc[k] = std::max(1, static_cast<int>(std::floor(c.box[k] / c.diameter)));
    nc[k] = std::min(nc[k], 1 << 20);
    cw[k] = c.box[k] / nc[k];
    total *= static_cast<std::size_t>(nc[k]);
  }
  require(total <= (std::size_t{1} << 31), "box has too many cells (more than 2^31)");
  std::vector<int> head(total, -1), next(n, -1);
  std::vector<std::array<int, 3>> cc(n);
  auto index = [&](const std::array<int, 3>& q) {
    std::size_t id = 0, stride = 1;
    for (int k = 0; k < d; ++k) {
      id += static_cast<std::size_t>(q[k]) * stride;
      stride *= static_cast<std::size_t>(nc[k]);
    }
    return id;
  };
  const double min2 = c.diameter * c.diameter * (1.0 - 1e-9) * (1.0 - 1e-9);
  for (std::size_t i = 0; i < n; ++i) {
    for (int k = 0; k < d; ++k) cc[i][k] = std::clamp(static_cast<int>(std::floor(x[i * d + k] / cw[k])), 0, nc[k] - 1);
    const int noff = d == 1 ? 3 : d == 2 ? 9 : 27;
    for (int o = 0; o < noff; ++o) {
      int rem = o;
      std::array<int, 3> q{0, 0, 0};
      std::array<double, 3> sh{0, 0, 0};
      bool ok = true;
      for (int k = 0; k < d; ++k) {
        int ck = cc[i][k] + rem % 3 - 1;
        rem /= 3;
        if (ck < 0 || ck >= nc[k]) {
          if (c.boundary[k] == Boundary::wall || nc[k] < 3) { ok = false; break; }
          if (ck < 0) { ck += nc[k]; sh[k] = -c.box[k]; } else { ck -= nc[k]; sh[k] = c.box[k]; }
        }
        q[k] = ck;
      }
      if (!ok) continue;
      for (int j = head[index(q)]; j >= 0; j = next[j]) {
        double r2 = 0.0;
        for (int k = 0; k < d; ++k) {
          const double dx = x[i * d + k] - (x[j * d + k] + sh[k]);
          r2 += dx * dx;
        }
        require(r2 >= min2, [&] {
          return "particles " + std::to_string(j) + " and " + std::to_string(i) + " overlap: distance " +
                 std::to_string(std::sqrt(r2)) + " < diameter " + std::to_string(c.diameter);
        });
      }
    }
    const std::size_t id = index(cc[i]);
    next[i] = head[id];
    head[id] = static_cast<int>(i);
  }
}

template <int Dim>
std::unique_ptr<Simulation> make_dim(const Config& c, const std::vector<double>& x, const std::vector<double>& v,
                                     double t0) {
  return std::make_unique<EngineImpl<Dim>>(c, x, v, t0);
}

}  // namespace

std::unique_ptr<Simulation> make_simulation(const Config& c, const std::vector<double>& x,
                                            const std::vector<double>& v, double t0) {
  require(std::isfinite(t0), "start time must be finite");
  validate_state(c, x, v);
  if (c.dim == 1) return make_dim<1>(c, x, v, t0);
  if (c.dim == 2) return make_dim<2>(c, x, v, t0);
  return make_dim<3>(c, x, v, t0);
}

std::unique_ptr<Simulation> restore_simulation(const Snapshot& s) {
  validate_config(s.config);
  const std::size_t n = s.n, d = static_cast<std::size_t>(s.config.dim);
  require(n > 0, "snapshot: no particles (N = 0)");
  require(s.x.size() == n * d && s.v.size() == n * d && s.cell.size() == n * d,
          "snapshot: x, v and cell must have n x dim entries");
  require(s.centre.empty() || s.centre.size() == n * d, "snapshot: centre must have n x dim entries (or none)");
  for (double q : s.centre) require(std::isfinite(q), "snapshot: list centres must be finite");
  require(s.t_local.size() == n && s.stamp.size() == n && s.ncoll.size() == n &&
              s.ev_t.size() == n && s.ev_kind.size() == n && s.ev_partner.size() == n && s.ev_stamp.size() == n &&
              s.second.size() == n && s.touching.size() == n,
          "snapshot: per-particle arrays must have n entries");
  require(s.rng.size() == (s.config.streams == rng::StreamPolicy::single ? 1 : n),
          "snapshot: rng must hold one draw count per stream (n, or 1 for a single stream)");
  require(std::isfinite(s.time) && std::isfinite(s.start_time), "snapshot: times must be finite");
  for (double t : s.t_local) require(std::isfinite(t), "snapshot: local times must be finite");
  for (double q : s.x) require(std::isfinite(q), "snapshot: positions must be finite");
  for (double q : s.v) require(std::isfinite(q), "snapshot: velocities must be finite");
  require(s.log_pushed >= s.log_cells.size(), "snapshot: log_pushed is smaller than the log");
  {
    require(s.pre_keys.size() == 2 * s.pre_sizes.size(), "snapshot: exact-pre log keys must be 2 per entry");
    require(s.netc.size() == n, "snapshot: netc must have n entries");
    require(s.wall_keys.size() == 2 * s.wall_sizes.size(), "snapshot: wall log keys must be 2 per entry");
    std::uint64_t wm = 0;
    for (auto q : s.wall_sizes) wm += q;
    require(wm == s.wall_masks.size() && wm == s.wall_ids.size() && wm == s.wall_netc.size() &&
                s.wall_times.size() == s.wall_sizes.size(),
            "snapshot: wall log sizes do not add up to its masks");
    for (auto q : s.wall_ids) require(q < n, "snapshot: wall log particle outside [0, n)");
    std::uint64_t total = 0;
    for (auto q : s.pre_sizes) total += q;
    require(total == s.pre_vals.size(), "snapshot: exact-pre log sizes do not add up to its values");
  }
  if (d == 1) return std::make_unique<EngineImpl<1>>(s);
  if (d == 2) return std::make_unique<EngineImpl<2>>(s);
  return std::make_unique<EngineImpl<3>>(s);
}

}  // namespace revcol::engine
