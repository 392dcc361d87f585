// Shared helpers of the binding files: numpy shapes (their text in messages, and "one entry
// of shape S, or a batch of shape (B, *S)"), the generator argument (exactly one of rng= or
// g=), and held invariants (momentum= and energy=). Conversion only, no physics.
#pragma once
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstddef>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "revcol/collide/common.hpp"
#include "revcol/error.hpp"
#include "revcol/rng/clcg4.hpp"
#include "revcol/rng/philox.hpp"

namespace revcol::bind {

/// A C-contiguous float64 array (other dtypes and layouts are converted).
using Array = pybind11::array_t<double, pybind11::array::c_style | pybind11::array::forcecast>;
/// A numpy shape.
using Shape = std::vector<pybind11::ssize_t>;

/// "(2, 3)", "(3,)", "()": a shape as Python prints it.
inline std::string shape_str(const Shape& s) {
  std::string out = "(";
  for (std::size_t k = 0; k < s.size(); ++k) out += (k ? ", " : "") + std::to_string(s[k]);
  return out + (s.size() == 1 ? ",)" : ")");
}
/// The shape of `a` as Python prints it.
inline std::string shape_of(const Array& a) { return shape_str(Shape(a.shape(), a.shape() + a.ndim())); }
/// The shape of `a`.
inline Shape shape(const Array& a) { return Shape(a.shape(), a.shape() + a.ndim()); }

/// How many entries an array holds, and whether it had the batch axis.
struct Rows {
  std::size_t count;  ///< B (1 without the batch axis)
  bool batched;       ///< shape (B, *inner) rather than inner
};
/// Whether `a` has shape `inner` (one entry) or (B, *inner) (B entries).
inline std::optional<Rows> match(const Array& a, const Shape& inner) {
  const auto n = static_cast<pybind11::ssize_t>(inner.size());
  auto tail = [&](pybind11::ssize_t off) {
    for (pybind11::ssize_t k = 0; k < n; ++k)
      if (a.shape(off + k) != inner[k]) return false;
    return true;
  };
  if (a.ndim() == n && tail(0)) return Rows{1, false};
  if (a.ndim() == n + 1 && tail(1)) return Rows{static_cast<std::size_t>(a.shape(0)), true};
  return std::nullopt;
}
/// Number of doubles in one entry of shape `inner`.
inline std::size_t entry_size(const Shape& inner) {
  std::size_t s = 1;
  for (pybind11::ssize_t k : inner) s *= static_cast<std::size_t>(k);
  return s;
}
/// `inner` with the batch axis B in front.
inline Shape batched(const Shape& inner, std::size_t B) {
  Shape out{static_cast<pybind11::ssize_t>(B)};
  out.insert(out.end(), inner.begin(), inner.end());
  return out;
}
/// "(n, d) or (B, n, d)": the shapes an entry array may have.
inline std::string one_or_batch(const Shape& inner) {
  std::string many = "(B";
  for (pybind11::ssize_t k : inner) many += ", " + std::to_string(k);
  return shape_str(inner) + " or " + many + ")";
}
/// Rows of `a`, or InvalidArgument "`name` must have shape S or (B, *S), got ...".
inline Rows rows_of(const Array& a, const Shape& inner, const char* name) {
  const auto m = match(a, inner);
  require(m.has_value(), [&] {
    return std::string(name) + " must have shape " + one_or_batch(inner) + ", got " + shape_of(a);
  });
  return *m;
}
/// `a` for B entries, shape `inner` (broadcast) or (B, *inner): each entry's data pointer.
inline std::vector<const double*> per_entry(const Array& a, const Shape& inner, std::size_t B,
                                            const char* name) {
  const auto m = match(a, inner);
  require(m && (!m->batched || m->count == B), [&] {
    return std::string(name) + " must have shape " + shape_str(inner) + " or " +
           shape_str(batched(inner, B)) + ", got " + shape_of(a);
  });
  std::vector<const double*> out(B);
  for (std::size_t b = 0; b < B; ++b) out[b] = a.data() + (m->batched ? b * entry_size(inner) : 0);
  return out;
}

/// Draws for B entries of d_n each: (d_n,) for one entry, (B, d_n) for a batch, and with
/// d_n = 1 also () for one entry and (B,) for any B. Returns them flat (B x d_n).
inline std::vector<double> draws_from(const Array& g, const Rows& rows, int d) {
  const std::size_t B = rows.count;
  const bool one = !rows.batched && g.ndim() == 1 && g.shape(0) == d;
  const bool many = rows.batched && g.ndim() == 2 && static_cast<std::size_t>(g.shape(0)) == B && g.shape(1) == d;
  const bool scalars = d == 1 && ((g.ndim() == 0 && B == 1) ||
                                  (g.ndim() == 1 && static_cast<std::size_t>(g.shape(0)) == B));
  require(one || many || scalars, [&] {
    const std::string dn = std::to_string(d), b = std::to_string(B);
    return "g must have shape " + (rows.batched ? "(" + b + ", " + dn + ")" : "(" + dn + ",)") +
           (d == 1 ? (rows.batched ? " or (" + b + ",)" : " or ()") : "") + ", got " + shape_of(g);
  });
  return std::vector<double>(g.data(), g.data() + B * static_cast<std::size_t>(d));
}

/// Runs f(draws) with g, or f(generator) with a revcol.CLCG4 or revcol.Philox: exactly one
/// of rng= and g= must be given.
template <class F>
void with_draws(const pybind11::object& rng, bool has_g, F&& f) {
  require(rng.is_none() != !has_g, "give exactly one of rng= (a generator) or g= (draws)");
  if (has_g) f(nullptr);
  else if (pybind11::isinstance<rng::CLCG4>(rng)) f(&rng.cast<rng::CLCG4&>());
  else if (pybind11::isinstance<rng::Philox>(rng)) f(&rng.cast<rng::Philox&>());
  else throw InvalidArgument("rng must be a revcol.CLCG4 or revcol.Philox");
}

/// Held momentum (d per entry) and energy (one per entry) for B entries: each of shape
/// (d,)/() (broadcast) or (B, d)/(B,); both or neither must be given.
struct HeldArrays {
  std::vector<const double*> momentum;  ///< entry b's d components (into the caller's array)
  std::vector<double> energy;           ///< entry b's energy
};
/// Parses momentum= and energy= for B entries of dimension d, or nothing when neither is
/// given. The pointers are into `momentum`, which must outlive the result.
inline std::optional<HeldArrays> held_from(const std::optional<Array>& momentum,
                                           const std::optional<Array>& energy, std::size_t B, int d) {
  require(momentum.has_value() == energy.has_value(),
          "give both momentum and energy (held invariants), or neither");
  if (!momentum) return std::nullopt;
  HeldArrays h{per_entry(*momentum, {d}, B, "momentum"), {}};
  for (const double* e : per_entry(*energy, {}, B, "energy")) h.energy.push_back(*e);
  return h;
}
/// The held invariants of B entries in dimension Dim, or nothing.
template <int Dim>
std::optional<std::vector<Invariants<Dim>>> invariants_from(const std::optional<Array>& momentum,
                                                            const std::optional<Array>& energy,
                                                            std::size_t B) {
  const auto h = held_from(momentum, energy, B, Dim);
  if (!h) return std::nullopt;
  std::vector<Invariants<Dim>> out(B);
  for (std::size_t b = 0; b < B; ++b) {
    for (int k = 0; k < Dim; ++k) out[b].momentum[k] = h->momentum[b][k];
    out[b].energy = h->energy[b];
  }
  return out;
}

}  // namespace revcol::bind
