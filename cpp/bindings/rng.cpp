// Bindings of revcol/rng: CLCG4, Philox and philox4x32. Type conversion and registration
// only; the generators live in cpp/include/revcol/rng/. Integers are range-checked here so
// that a negative or too-large value is a ValueError (revcol's InvalidArgument), as the
// C++ core reports bad values, and not pybind11's generic TypeError.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <array>
#include <cstdint>
#include <string>

#include "args.hpp"
#include "bindings.hpp"
#include "revcol/error.hpp"
#include "revcol/rng/clcg4.hpp"
#include "revcol/rng/philox.hpp"

namespace py = pybind11;
using revcol::InvalidArgument;
using revcol::rng::CLCG4;
using revcol::rng::Philox;
using revcol::bind::PyInt;
using revcol::bind::to_int;

namespace {

constexpr std::uint64_t kMaxU32 = 0xffffffffULL;
constexpr std::uint64_t kMaxU64 = ~0ULL;

// A Python integer (anything with __index__) in [0, max]; a non-integer is a TypeError, an
// integer out of range an InvalidArgument (ValueError) naming `what`.
std::uint64_t to_uint(py::handle obj, std::uint64_t max, const std::string& what) {
  PyObject* index = PyNumber_Index(obj.ptr());
  if (index == nullptr) throw py::error_already_set();
  const py::object value = py::reinterpret_steal<py::object>(index);
  const unsigned long long x = PyLong_AsUnsignedLongLong(value.ptr());
  if (x == static_cast<unsigned long long>(-1) && PyErr_Occurred()) {
    PyErr_Clear();  // negative or >= 2^64
    throw InvalidArgument(what + " = " + std::string(py::str(value)) + " is outside [0, " + std::to_string(max) + "]");
  }
  if (x > max) throw InvalidArgument(what + " = " + std::to_string(x) + " is outside [0, " + std::to_string(max) + "]");
  return x;
}

// A sequence of exactly N integers, each in [0, 2^32 - 1].
template <std::size_t N>
std::array<std::uint32_t, N> to_words(py::handle obj, const std::string& what) {
  if (!PySequence_Check(obj.ptr()) || py::isinstance<py::str>(obj) || py::isinstance<py::bytes>(obj))
    throw py::type_error(what + " must be a sequence of " + std::to_string(N) + " integers");
  const auto seq = py::reinterpret_borrow<py::sequence>(obj);
  if (seq.size() != N)
    throw InvalidArgument(what + " must have " + std::to_string(N) + " words, got " + std::to_string(seq.size()));
  std::array<std::uint32_t, N> out{};
  for (std::size_t i = 0; i < N; ++i)
    out[i] = static_cast<std::uint32_t>(to_uint(seq[i], kMaxU32, what + "[" + std::to_string(i) + "]"));
  return out;
}

template <std::size_t N>
py::tuple to_tuple(const std::array<std::uint32_t, N>& w) {
  py::tuple t(N);
  for (std::size_t i = 0; i < N; ++i) t[i] = py::int_(w[i]);
  return t;
}

std::size_t to_count(const PyInt& n) {
  return to_int<std::size_t>(n, "n", 0, std::size_t{1} << 40);  // 2^40 draws = 8 TiB: beyond any memory
}

// n draws (Forward) or n undone draws (!Forward, values in the order undone) into a new
// float64 array. The loop runs on a local copy of the generator so its state stays in
// registers; the caller has checked that nothing in the loop can throw.
template <bool Forward, class Gen>
py::array_t<double> draw_many(Gen& g, std::size_t n) {
  py::array_t<double> out(static_cast<py::ssize_t>(n));
  double* p = out.mutable_data();
  Gen local = g;
  for (std::size_t i = 0; i < n; ++i) p[i] = Forward ? local.next() : local.prev();
  g = local;
  return out;
}

void set_clcg4_state(CLCG4& g, py::handle obj) {
  // Words out of 32-bit range are reported per component here; set_state checks [1, m_j - 1].
  if (!PySequence_Check(obj.ptr()) || py::isinstance<py::str>(obj) || py::isinstance<py::bytes>(obj))
    throw py::type_error("CLCG4 state must be a sequence of 4 integers");
  const auto seq = py::reinterpret_borrow<py::sequence>(obj);
  if (seq.size() != 4) throw InvalidArgument("CLCG4 state must have 4 components, got " + std::to_string(seq.size()));
  CLCG4::State s{};
  for (std::size_t j = 0; j < 4; ++j)
    s[j] = static_cast<std::uint32_t>(to_uint(seq[j], kMaxU32, "CLCG4 state component s_" + std::to_string(j)));
  g.set_state(s);
}

CLCG4 clcg4_from_state(py::handle obj) {
  CLCG4 g;
  set_clcg4_state(g, obj);
  return g;
}

std::string clcg4_repr(const CLCG4& g) {
  const auto s = g.state();
  return "CLCG4.from_state((" + std::to_string(s[0]) + ", " + std::to_string(s[1]) + ", " + std::to_string(s[2]) +
         ", " + std::to_string(s[3]) + "))";
}

std::string philox_repr(const Philox& p) {
  const auto k = p.key();
  return "Philox(key=(" + std::to_string(k[0]) + ", " + std::to_string(k[1]) + "), counter=" +
         std::to_string(p.counter()) + ")";
}

const char* const kCLCG4Doc = R"doc(
Reversible combined LCG of L'Ecuyer & Andres (1997), "CLCG4", period about 2^121.

Four multiplicative LCGs, j = 0..3, with prime moduli m_j < 2^31::

    next:  s_j <- a_j s_j mod m_j,  then  u = (s_0/m_0 - s_1/m_1 + s_2/m_2 - s_3/m_3) mod 1
    prev:  returns the u of the current state, then  s_j <- b_j s_j mod m_j,  b_j = a_j^-1

u is evaluated in double precision exactly as in the published code (term by term,
s_j * (1/m_j), with a wrap after each term), so outputs are bit-reproducible; u is in [0, 1].
``next(); prev()`` is the identity and ``prev()`` returns the value the undone ``next()``
returned (the paper's RNG^-1).

Stream k starts at seed_j a_j^(k 2^72) mod m_j (default seed 11111111, 22222222,
33333333, 44444444); substream s of it at that times a_j^(s 2^41).

Example::

    >>> g = revcol.CLCG4(stream=0)
    >>> u = g.next()          # 0.90587718250437343
    >>> g.prev() == u
    True
    >>> g.state
    (11111111, 22222222, 33333333, 44444444)
)doc";

const char* const kPhiloxDoc = R"doc(
Counter-based Philox4x32-10 generator (Salmon et al., SC'11; Random123), reversible by
decrementing the counter.

Draw k is a pure function of (key, k)::

    (w0, w1, w2, w3) = philox4x32((k mod 2^32, k >> 32, 0, 0), key)
    B = (w0 << 21) ^ (w1 >> 11)             # 53 random bits
    u = (B + 1/2) 2^-53                     # in double; strictly inside (0, 1)

(for B >= 2^52 the +1/2 rounds to even in double; the single pattern B = 2^53 - 1 is
returned as 1 - 2^-53 rather than 1.0). ``next()`` returns ``at(counter)`` and increments
the counter; ``prev()`` decrements it and returns ``at(counter)`` (ValueError at 0).

Example::

    >>> p = revcol.Philox(key=(7, 0))
    >>> u = p.next()
    >>> p.at(0) == u, p.counter
    (True, 1)
    >>> p.prev() == u
    True
)doc";

}  // namespace

namespace revcol::bind {

void register_rng(py::module_& m) {
  py::class_<CLCG4>(m, "CLCG4", kCLCG4Doc)
      .def(py::init([](py::handle stream, py::handle substream) {
             return CLCG4(to_uint(stream, kMaxU64, "stream"), to_uint(substream, kMaxU64, "substream"));
           }),
           py::arg("stream") = 0, py::arg("substream") = 0,
           "Start of substream `substream` of stream `stream`: s_j = seed_j a_j^(stream 2^72 + substream 2^41) mod m_j.")
      .def_static("from_state", &clcg4_from_state, py::arg("state"),
                  "A generator at this state (four ints, s_j in [1, m_j - 1]; ValueError otherwise).")
      .def("next", &CLCG4::next, "Step forward and return u in [0, 1].")
      .def("prev", &CLCG4::prev,
           "Return the value the last next() returned, then step back: next(); prev() is the identity.")
      .def(
          "next_many",
          [](CLCG4& g, PyInt n) { return draw_many<true>(g, to_count(n)); },
          py::arg("n"), "n draws as a float64 array, in draw order (same as n calls of next()).")
      .def(
          "prev_many",
          [](CLCG4& g, PyInt n) { return draw_many<false>(g, to_count(n)); },
          py::arg("n"),
          "Undo n draws; float64 array in the order they are undone, i.e. REVERSED draw order:\n"
          "after a = g.next_many(n), g.prev_many(n) equals a[::-1] and the state is restored.")
      .def_property(
          "state", [](const CLCG4& g) { return to_tuple(g.state()); }, &set_clcg4_state,
          "The state (s_0, s_1, s_2, s_3). Setting validates s_j in [1, m_j - 1]: a bad value raises\n"
          "ValueError and leaves the state unchanged.")
      .def_property_readonly_static("modulus", [](py::handle) { return to_tuple(CLCG4::modulus); }, "Moduli m_j.")
      .def_property_readonly_static("multiplier", [](py::handle) { return to_tuple(CLCG4::multiplier); },
                                    "Multipliers a_j.")
      .def_property_readonly_static("inverse_multiplier",
                                    [](py::handle) { return to_tuple(CLCG4::inverse_multiplier); },
                                    "Inverse multipliers b_j = a_j^-1 mod m_j.")
      .def("__eq__", [](const CLCG4& a, const CLCG4& b) { return a == b; }, py::is_operator())
      .def("__repr__", &clcg4_repr)
      .def(py::pickle([](const CLCG4& g) { return py::make_tuple(to_tuple(g.state())); },
                      [](const py::tuple& t) {
                        if (t.size() != 1) throw InvalidArgument("bad CLCG4 pickle");
                        return clcg4_from_state(t[0]);
                      }));

  py::class_<Philox>(m, "Philox", kPhiloxDoc)
      .def(py::init([](py::handle key, py::handle counter) {
             return Philox(to_words<2>(key, "key"), to_uint(counter, kMaxU64, "counter"));
           }),
           py::arg("key") = py::make_tuple(0, 0), py::arg("counter") = 0,
           "A stream with this key (two 32-bit words) whose next draw is draw `counter`.")
      .def(
          "next",
          [](Philox& g) {
            // the counter is 64 bits: the draw at 2^64 - 1 would wrap it to 0, after which prev()
            // could never return it (the stream would lose its place); refused, nothing changed
            if (g.counter() == kMaxU64) throw InvalidArgument("Philox: the stream is at its last counter (2^64 - 1); next() would wrap it to 0");
            return g.next();
          },
          "Return draw at(counter) and increment the counter; ValueError at counter 2^64 - 1 (it would wrap).")
      .def("prev", &Philox::prev,
           "Decrement the counter and return that draw (the value the last next() returned); ValueError at 0.")
      .def(
          "at", [](const Philox& p, py::handle k) { return p.at(to_uint(k, kMaxU64, "k")); }, py::arg("k"),
          "Draw k, in (0, 1), without changing the counter.")
      .def(
          "next_many",
          [](Philox& g, PyInt n) {
            const std::size_t count = to_count(n);
            if (count > kMaxU64 - g.counter())
              throw InvalidArgument("Philox: " + std::to_string(count) + " draws from counter " + std::to_string(g.counter()) +
                                    " would pass 2^64 - 1 and wrap the counter");
            return draw_many<true>(g, count);
          },
          py::arg("n"), "n draws as a float64 array, in draw order (same as n calls of next()).")
      .def(
          "prev_many",
          [](Philox& g, PyInt n) {
            const std::size_t count = to_count(n);
            if (count > g.counter())
              throw InvalidArgument("Philox: cannot step back before draw 0 (counter " + std::to_string(g.counter()) +
                                    ", n " + std::to_string(count) + ")");
            return draw_many<false>(g, count);  // cannot throw now: count <= counter
          },
          py::arg("n"),
          "Undo n draws; float64 array in the order they are undone, i.e. REVERSED draw order:\n"
          "after a = p.next_many(n), p.prev_many(n) equals a[::-1]. ValueError (nothing changed) if n > counter.")
      .def_property(
          "counter", &Philox::counter,
          [](Philox& p, py::handle c) { p.set_counter(to_uint(c, kMaxU64, "counter")); },
          "Index of the next draw (0 <= counter < 2^64); settable.")
      .def_property_readonly(
          "key", [](const Philox& p) { return to_tuple(p.key()); }, "The key (k0, k1).")
      .def("__eq__", [](const Philox& a, const Philox& b) { return a == b; }, py::is_operator())
      .def("__repr__", &philox_repr)
      .def(py::pickle([](const Philox& p) { return py::make_tuple(to_tuple(p.key()), p.counter()); },
                      [](const py::tuple& t) {
                        if (t.size() != 2) throw InvalidArgument("bad Philox pickle");
                        return Philox(to_words<2>(t[0], "key"), to_uint(t[1], kMaxU64, "counter"));
                      }));

  m.def(
      "philox4x32",
      [](py::handle counter, py::handle key) {
        return to_tuple(revcol::rng::philox4x32_10(to_words<4>(counter, "counter"), to_words<2>(key, "key")));
      },
      py::arg("counter"), py::arg("key"),
      R"doc(Random123 Philox4x32-10 block: a 4-word counter and a 2-word key (32-bit ints) to 4 words.

Ten rounds of (c0, c1, c2, c3) <- (hi(M1 c2) ^ c1 ^ k0, lo(M1 c2), hi(M0 c0) ^ c3 ^ k1, lo(M0 c0)),
the key bumped by (0x9E3779B9, 0xBB67AE85) between rounds; M0 = 0xD2511F53, M1 = 0xCD9E8D57.

Example::

    >>> [hex(w) for w in revcol.philox4x32((0, 0, 0, 0), (0, 0))]
    ['0x6627e8d5', '0xe169c58d', '0xbc57ac4c', '0x9b00dbd8']
)doc");
}

}  // namespace revcol::bind
