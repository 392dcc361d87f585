// The word stream of randomness.hpp: generators (good and bad), the forward chain over
// every operator signature, and the chart that maps a post state to words.
#include "revcol/studies/randomness.hpp"

#include <algorithm>
#include <cstdio>
#include <functional>
#include <limits>

#include "revcol/collide/cases.hpp"
#include "revcol/collide/pair2d_exact.hpp"
#include "revcol/collide/pair2d_paper.hpp"
#include "revcol/engine/engine.hpp"
#include "revcol/engine/init.hpp"
#include "revcol/engine/limits.hpp"
#include "revcol/engine/observe.hpp"
#include "revcol/error.hpp"
#include "revcol/rng/clcg4.hpp"
#include "revcol/rng/philox.hpp"
#include "revcol/rng/streams.hpp"
#include "revcol/studies/paper_adapt.hpp"

namespace revcol::randomness {
namespace {

// --- generators ------------------------------------------------------------------------

struct Uniforms {
  virtual ~Uniforms() = default;
  virtual double next() = 0;
};

template <class G>
struct Wrapped final : Uniforms {
  G g;
  explicit Wrapped(G gen) : g(std::move(gen)) {}
  double next() override { return g.next(); }
};

// RANDU: x <- 65539 x mod 2^31 from an odd start; G = x / 2^31 in (0, 1). Its outputs obey
// x_(k+2) = 6 x_(k+1) - 9 x_k (mod 2^31): every triple lies on one of 15 planes.
struct Randu final : Uniforms {
  std::uint32_t x;
  explicit Randu(std::uint64_t seed) : x(static_cast<std::uint32_t>((2 * seed + 1) & 0x7fffffffu)) {}
  double next() override {
    x = static_cast<std::uint32_t>((65539ull * x) & 0x7fffffffull);
    return x * 0x1.0p-31;
  }
};

// Philox whose every 100th draw repeats the draw before it (a subtle defect: 1% of draws).
struct Repeat100 final : Uniforms {
  rng::Philox g;
  std::uint64_t count = 0;
  double last = 0.5;
  explicit Repeat100(rng::Philox gen) : g(gen) {}
  double next() override {
    if (++count % 100 != 0) last = g.next();
    return last;
  }
};

std::unique_ptr<Uniforms> make_uniforms(const StreamConfig& c) {
  if (c.rng == "clcg4") return std::make_unique<Wrapped<rng::CLCG4>>(rng::make_generator<rng::CLCG4>(0, c.seed, 1));
  if (c.rng == "philox") return std::make_unique<Wrapped<rng::Philox>>(rng::make_generator<rng::Philox>(0, c.seed, 1));
  if (c.rng == "randu") return std::make_unique<Randu>(c.seed);
  if (c.rng == "philox-repeat100") return std::make_unique<Repeat100>(rng::make_generator<rng::Philox>(0, c.seed, 1));
  throw InvalidArgument("rng must be clcg4, philox, randu or philox-repeat100, got '" + c.rng + "'");
}

// --- sources: one collision (or one draw) per step, its coordinates in [0,1) ---------------

struct Source {
  virtual ~Source() = default;
  virtual int width() const = 0;
  virtual void step(Uniforms& gen, double* u) = 0;
  std::uint64_t restarts = 0;
  std::uint64_t skipped = 0;  // gas: group collisions (no words)
};

struct Raw final : Source {
  int width() const override { return 1; }
  void step(Uniforms& gen, double* u) override { u[0] = gen.next(); }
};

template <int Dim>
void negate(PairV<Dim>& v) {
  for (int k = 0; k < Dim; ++k) { v.i[k] = -v.i[k]; v.j[k] = -v.j[k]; }
}
template <std::size_t Dim>
void negate(std::array<std::array<double, Dim>, 3>& v) {  // paper::Triple<Dim>
  for (auto& p : v)
    for (double& x : p) x = -x;
}
void negate(std::vector<double>& v) {
  for (double& x : v) x = -x;
}

// The paper's illustration forward only: draws, collision t, map the post state, negate it.
// forward(pre, g, post, t) throws InvalidArgument on a state it refuses; valid(post) says
// whether the post state separates. With may_fail (paper mode) a refused or invalid step
// restarts the chain from its start; otherwise the exception propagates.
template <class State>
class Chain final : public Source {
 public:
  using Forward = std::function<void(const State&, const double*, State&, std::uint64_t)>;
  using Valid = std::function<bool(const State&)>;
  using Map = std::function<void(const State&, double*)>;

  Chain(State start, int draws, bool may_fail, Forward f, Valid valid, Map map)
      : start_(start), v_(start), post_(start), g_(draws), may_fail_(may_fail),
        forward_(std::move(f)), valid_(std::move(valid)), map_(std::move(map)) {}
  int width() const override { return static_cast<int>(g_.size()); }
  void step(Uniforms& gen, double* u) override {
    for (int fails = 0;; ++fails) {
      require(fails < 1000, "the chain failed 1000 times in a row: no valid collision from this start");
      for (double& g : g_) g = gen.next();
      bool ok = false;
      try {
        forward_(v_, g_.data(), post_, t_);
        ok = valid_(post_);
      } catch (const InvalidArgument&) {
        if (!may_fail_) throw;
      }
      require(ok || may_fail_, "exact-mode post state does not separate");
      if (!ok) {
        v_ = start_;
        t_ = 0;
        ++restarts;
        continue;
      }
      map_(post_, u);
      v_ = post_;
      negate(v_);  // reverse the velocities to create the next collision
      ++t_;
      return;
    }
  }

 private:
  State start_, v_, post_;
  std::vector<double> g_;
  bool may_fail_;
  Forward forward_;
  Valid valid_;
  Map map_;
  std::uint64_t t_ = 0;
};

// --- the cases -----------------------------------------------------------------------------

// pair2d in either mode: verify()'s start and normal (1, 1), invariants held; the words are
// the chart of `mapper` (the exact operator of the mapping law).
template <class Op>
std::unique_ptr<Source> pair2d(Op op, Law cdf_law, int bits, bool may_fail) {
  const PairV<2> v{{0.25, -0.5}, {1.0, 0.75}};
  const std::array<double, 2> n{1.0, 1.0};
  const Invariants<2> inv{{v.i[0] + v.j[0], v.i[1] + v.j[1]},
                          v.i[0] * v.i[0] + v.i[1] * v.i[1] + v.j[0] * v.j[0] + v.j[1] * v.j[1]};
  op.check_pre(v, n, &inv);
  const Frame2 f(n);
  const Pair2DExact mapper(cdf_law, bits);
  auto log = std::make_shared<RareLog>();
  return std::make_unique<Chain<PairV<2>>>(
      v, 1, may_fail,
      [op, n, inv, log](const PairV<2>& pre, const double* g, PairV<2>& post, std::uint64_t) {
        post = op.forward(pre, n, g[0], *log, &inv);
        log->clear();  // never reversed: nothing to keep
      },
      [f](const PairV<2>& post) { return f.normal_part(relative(post)) > 0.0; },
      [f, mapper](const PairV<2>& post, double* u) {
        const std::array<double, 2> w = relative(post);
        u[0] = mapper.chart(f.normal_part(w), f.tangent_part(w), std::hypot(w[0], w[1]));
      });
}

// The chain's first pre state: a Newton's cradle starts at rest but for particle 0, which
// moves towards the others (verify_exact.cpp's start: v_0 = 1, in 2D (1, 1/4)); every other
// case from approaching_state(op, 1).
std::vector<double> start_state(const NamedCase& nc, const ExactCollision& op) {
  if (nc.name.rfind("cradle", 0) != 0) return approaching_state(op, 1);
  std::vector<double> v(static_cast<std::size_t>(nc.n * nc.d), 0.0);
  v[0] = 1.0;
  if (nc.d > 1) v[1] = 0.25;
  return v;
}

// Every named case in exact mode through the general operator (verify_exact.cpp's chain:
// the held momentum follows the sign of the negated velocities).
std::unique_ptr<Source> exact_case(const NamedCase& nc, const StreamConfig& c) {
  auto op = std::make_shared<const ExactCollision>(exact_operator(nc, c.law, c.bits));
  auto mapper = std::make_shared<const ExactCollision>(exact_operator(nc, c.cdf_law, c.bits));
  require(op->draws() >= 1, [&] { return nc.name + " has no free parameter (d_n = 0): no words"; });
  const std::vector<double> v = start_state(nc, *op);
  auto mp = std::make_shared<std::vector<double>>(nc.d, 0.0);
  auto mn = std::make_shared<std::vector<double>>(nc.d, 0.0);
  double e = 0.0;
  for (int i = 0; i < nc.n; ++i)
    for (int a = 0; a < nc.d; ++a) {
      (*mp)[a] += v[i * nc.d + a];
      e += v[i * nc.d + a] * v[i * nc.d + a];
    }
  for (int a = 0; a < nc.d; ++a) (*mn)[a] = -(*mp)[a];
  auto log = std::make_shared<RareLog>();
  return std::make_unique<Chain<std::vector<double>>>(
      v, op->draws(), false,
      [op, mp, mn, e, log](const std::vector<double>& pre, const double* g, std::vector<double>& post,
                           std::uint64_t t) {
        const Held h{t % 2 ? mn->data() : mp->data(), e};
        op->forward(pre.data(), g, post.data(), *log, &h);
        log->clear();
      },
      [op](const std::vector<double>& post) {
        for (double s : op->normal_speeds(post.data()))
          if (!(s > 0.0)) return op->logs(post.data());  // the rare log serves it
        return true;
      },
      [mapper](const std::vector<double>& post, double* u) {
        const std::vector<double> ch = mapper->chart_unchecked(post.data());
        for (std::size_t k = 0; k < ch.size(); ++k) u[k] = ch[k];
      });
}

// A paper-mode case of paper_study (pair3d, triple1d, triple2d-c1..c4): verify_paper.cpp's
// chain, mapped by the exact operator's uniform chart of the same geometry.
template <class Op>
std::unique_ptr<Source> paper_chain(const paper::PaperCase& pc, const StreamConfig& c) {
  using A = paper::adapt::Adapter<Op>;
  const Op op = A::make(paper::StudyConfig{});
  const typename Op::Geometry x = A::geometry(pc.geometry);
  const typename Op::State v = A::state(pc.velocities);
  const typename Op::Inv inv = A::invariants(v);
  op.check_pre(v, x, &inv);
  const typename A::Pred pred(x);
  auto mapper = std::make_shared<const ExactCollision>(exact_operator(named_case(pc.name), c.cdf_law, c.bits));
  auto log = std::make_shared<RareLog>();
  using State = typename Op::State;
  return std::make_unique<Chain<State>>(
      v, Op::draws, true,
      [op, x, inv, log](const State& pre, const double* g, State& post, std::uint64_t) {
        typename Op::Draws d;
        for (std::size_t k = 0; k < d.size(); ++k) d[k] = g[k];
        post = op.forward(pre, x, d, *log, &inv);
        log->clear();
      },
      [pred](const State& post) { return pred.separates(post); },
      [mapper](const State& post, double* u) {
        const std::vector<double> f = A::flat(post);
        const std::vector<double> ch = mapper->chart_unchecked(f.data());
        for (std::size_t k = 0; k < ch.size(); ++k) u[k] = ch[k];
      });
}

// --- the engine's collisions in a gas -------------------------------------------------------

// The direction of a pair's post relative velocity w about its contact normal a (unit) as d - 1
// CDF values of the law (randomness.hpp): 2D the signed angle eta from a, 3D the polar angle
// eta and the azimuth phi in the frame of pair3d_exact.hpp (t1 along e_k x a, e_k the axis
// least aligned with a; t2 = a x t1).
void gas_chart(int dim, Law law, const double* a, const double* w, double* u) {
  constexpr double kPi = engine::limits::kPi;
  if (dim == 2) {
    const double p = w[0] * a[0] + w[1] * a[1], q = w[1] * a[0] - w[0] * a[1];
    u[0] = law == Law::flux ? 0.5 * (1.0 + q / std::hypot(p, q)) : std::atan2(q, p) / kPi + 0.5;
    return;
  }
  int k = 0;
  for (int j = 1; j < 3; ++j)
    if (std::fabs(a[j]) < std::fabs(a[k])) k = j;
  double t1[3] = {0.0, 0.0, 0.0};  // e_k x a
  t1[(k + 1) % 3] = -a[(k + 2) % 3];
  t1[(k + 2) % 3] = a[(k + 1) % 3];
  const double s = 1.0 / std::hypot(t1[0], t1[1], t1[2]);
  for (double& x : t1) x *= s;
  const double t2[3] = {a[1] * t1[2] - a[2] * t1[1], a[2] * t1[0] - a[0] * t1[2], a[0] * t1[1] - a[1] * t1[0]};
  double p = 0.0, q1 = 0.0, q2 = 0.0;
  for (int j = 0; j < 3; ++j) {
    p += w[j] * a[j];
    q1 += w[j] * t1[j];
    q2 += w[j] * t2[j];
  }
  const double T = q1 * q1 + q2 * q2, N = std::sqrt(p * p + T);
  u[0] = law == Law::flux ? T / (p * p + T) : (p > 0.0 ? T / (N * (N + p)) : 1.0 - p / N);
  const double phi = std::atan2(q2, q1) / (2.0 * kPi);
  u[1] = phi < 0.0 ? phi + 1.0 : phi;
}

// A periodic gas of the float engine in exact mode: each pair collision's post direction
// about its normal, read by gas_chart through cdf_law. The engine runs in chunks, each with
// a fresh observation whose collision record (observe.hpp) holds the chunk's pair
// collisions; group collisions give no word (counted in `skipped`).
class Gas final : public Source {
 public:
  Gas(const StreamConfig& c, int dim) : dim_(dim), law_(c.cdf_law) {
    require(c.mode == Mode::exact, "the gas streams run in exact mode only");
    require(c.rng == "philox" || c.rng == "clcg4", [&] { return "a gas stream's rng must be philox or clcg4, got '" + c.rng + "'"; });
    require(c.seed < (std::uint64_t{1} << 32), "a gas stream's seed must be < 2^32");
    require(c.gas_particles >= 2, "a gas needs at least 2 particles");
    require(std::isfinite(c.gas_warmup) && c.gas_warmup >= 0.0 && c.gas_warmup <= 1e6,
            "gas warm-up must be in [0, 1e6] collisions per particle");
    engine::Config ec;
    ec.dim = dim;
    ec.mode = Mode::exact;
    ec.law = c.law;
    ec.bits = c.bits;
    ec.seed = static_cast<std::uint32_t>(c.seed);
    ec.generator = engine::parse_generator(c.rng);
    const engine::InitialState s = engine::random_state(ec, c.gas_particles, c.gas_fraction, c.seed);
    sim_ = engine::make_simulation(s.config, s.x, s.v);
    const double warm = std::ceil(0.5 * c.gas_warmup * static_cast<double>(c.gas_particles));
    if (warm > 0.0) sim_->run(static_cast<std::uint64_t>(warm), kInf);  // a collision moves 2 particles
  }
  int width() const override { return dim_ - 1; }
  void step(Uniforms&, double* u) override {
    while (at_ == record_.size()) refill();
    gas_chart(dim_, law_, &record_[at_], &record_[at_ + dim_], u);
    at_ += 2 * static_cast<std::size_t>(dim_);
  }

 private:
  static constexpr double kInf = std::numeric_limits<double>::infinity();
  static constexpr std::uint64_t kChunk = 1 << 16;  // collisions per observation
  void refill() {
    engine::ObserveConfig oc;
    oc.collision_record = true;
    sim_->observe(oc);
    const std::uint64_t groups = sim_->diagnostics().counters.group_collisions;
    const engine::RunResult r = sim_->run(kChunk, kInf);
    require(r.collisions > 0, "the gas made no collision");
    skipped += sim_->diagnostics().counters.group_collisions - groups;
    record_ = sim_->observer()->collision_record();
    sim_->stop_observing();
    at_ = 0;
  }
  int dim_;
  Law law_;
  std::unique_ptr<engine::Simulation> sim_;
  std::vector<double> record_;
  std::size_t at_ = 0;
};

std::unique_ptr<Source> make_source(const StreamConfig& c) {
  FixedPoint check_bits(c.bits);  // validates K
  (void)check_bits;
  if (c.case_name == "raw") return std::make_unique<Raw>();
  if (c.case_name == "gas2d" || c.case_name == "gas3d") return std::make_unique<Gas>(c, c.case_name[3] - '0');
  if (c.mode == Mode::exact) {
    if (c.case_name == "pair2d") return pair2d(Pair2DExact(c.law, c.bits), c.cdf_law, c.bits, false);
    for (const NamedCase& nc : named_cases())
      if (nc.name == c.case_name) return exact_case(nc, c);
  } else if (c.mode == Mode::paper) {
    if (c.case_name == "pair2d") return pair2d(Pair2DPaper(), c.cdf_law, c.bits, true);
    for (const paper::PaperCase& pc : paper::paper_cases()) {
      if (pc.name != c.case_name) continue;
      if (pc.name == "pair3d") return paper_chain<Pair3DPaper>(pc, c);
      if (pc.name == "triple1d") return paper_chain<Triple1DPaper>(pc, c);
      return paper_chain<Triple2DPaper>(pc, c);
    }
  }
  std::string known;
  for (const std::string& n : stream_cases(c.mode)) known += (known.empty() ? "" : ", ") + n;
  throw InvalidArgument("no word stream for case '" + c.case_name + "' in mode " + to_string(c.mode) +
                        " (known: " + known + ")");
}

}  // namespace

std::vector<std::string> stream_cases(Mode mode) {
  std::vector<std::string> out{"raw", "pair2d"};
  if (mode == Mode::exact) {
    for (const NamedCase& nc : named_cases())
      if (nc.name != "pair2d" && (nc.n - 1) * nc.d >= 2) out.push_back(nc.name);
    out.push_back("gas2d");
    out.push_back("gas3d");
  } else if (mode == Mode::paper) {
    for (const paper::PaperCase& pc : paper::paper_cases()) out.push_back(pc.name);
  }
  return out;
}

struct WordStream::Impl {
  StreamConfig config;
  std::unique_ptr<Uniforms> gen;
  std::unique_ptr<Source> source;
  std::vector<double> pending;  // coordinates of the last step not yet emitted
  std::size_t next = 0;
  std::uint64_t steps = 0, words = 0;
};

WordStream::WordStream(const StreamConfig& config) : impl_(std::make_unique<Impl>()) {
  require(config.mode == Mode::exact || config.mode == Mode::paper, "mode must be exact or paper");
  impl_->config = config;
  impl_->gen = make_uniforms(config);
  impl_->source = make_source(config);
  impl_->pending.resize(impl_->source->width());
  impl_->next = impl_->pending.size();
}
WordStream::~WordStream() = default;
WordStream::WordStream(WordStream&&) noexcept = default;
WordStream& WordStream::operator=(WordStream&&) noexcept = default;

const StreamConfig& WordStream::config() const { return impl_->config; }
int WordStream::width() const { return impl_->source->width(); }
std::uint64_t WordStream::collisions() const { return impl_->steps; }
std::uint64_t WordStream::words() const { return impl_->words; }
std::uint64_t WordStream::restarts() const { return impl_->source->restarts; }
std::uint64_t WordStream::skipped() const { return impl_->source->skipped; }

void WordStream::fill(std::uint32_t* out, std::size_t n, const InterruptCheck& interrupt) {
  Impl& s = *impl_;
  constexpr std::size_t kChunk = std::size_t{1} << 16;  // words between interrupt checks
  for (std::size_t at = 0; at < n;) {
    const std::size_t end = std::min(n, at + kChunk);
    for (std::size_t k = at; k < end; ++k) {
      if (s.next == s.pending.size()) {
        s.source->step(*s.gen, s.pending.data());
        ++s.steps;
        s.next = 0;
      }
      out[k] = to_word(s.pending[s.next++]);
    }
    s.words += end - at;
    at = end;
    if (at < n && interrupt && interrupt()) throw Interrupted{};
  }
}

void WordStream::write(const std::string& path, std::uint64_t n, const InterruptCheck& interrupt) {
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "ab"), &std::fclose);
  require(f != nullptr, [&] { return "cannot open '" + path + "' for writing"; });
  std::vector<std::uint32_t> buf(1 << 16);
  bool ok = true;
  while (n > 0 && ok) {
    const std::size_t k = n < buf.size() ? static_cast<std::size_t>(n) : buf.size();
    fill(buf.data(), k);  // may throw (a paper chain that cannot go on): the file is closed
    ok = std::fwrite(buf.data(), sizeof(std::uint32_t), k, f.get()) == k;
    n -= k;
    if (n > 0 && ok && interrupt && interrupt()) {
      ok = std::fclose(f.release()) == 0;
      require(ok, [&] { return "writing '" + path + "' failed (disk full?)"; });
      throw Interrupted{};  // the file holds every word the stream moved past
    }
  }
  ok = std::fclose(f.release()) == 0 && ok;
  require(ok, [&] { return "writing '" + path + "' failed (disk full?)"; });
}

}  // namespace revcol::randomness
