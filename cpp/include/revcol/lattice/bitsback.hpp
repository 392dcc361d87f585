// The bits-back integer X of the lattice pair operator (LATTICE.md §3.3, docs/lattice.md).
//
// X is one unsigned integer of any size, stored as 64-bit words, least significant first,
// with no leading zero word (so equal values have equal word vectors; zero is no word).
// The pair operator moves information in and out of it with exactly invertible steps:
//   uniform push/pop over m values:   X -> X*m + idx          /  idx = X mod m, X -> X div m
//   rANS push/pop of a symbol with frequency f >= 1 at cumulative c, out of M = 2^48:
//                                      X -> (X div f)*M + (X mod f) + c
//                                      /  s = X mod M (c <= s < c+f), X -> f*(X div M) + s - c
//   the torus shift of the low 48 bits by G:  s = X mod M -> (s + G) mod M, the rest kept.
// Each pop is the exact inverse of the matching push (and add_low48 of sub_low48), so a
// sequence of them run backwards restores X bit for bit. Pushes grow X by about log2(m) or
// log2(M/f) bits, pops shrink it by as much: X stays bounded when these balance on average
// (the flux law) and drifts otherwise (the uniform law).
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace revcol::lattice {

/// The bits-back integer X: unsigned, any size (64-bit words, least significant first).
class BitsBack {
 public:
  static constexpr int rans_bits = 48;                        ///< M = 2^48, the rANS total
  static constexpr std::uint64_t rans_total = 1ULL << 48;     ///< M
  static constexpr std::uint64_t rans_mask = rans_total - 1;  ///< M - 1

  BitsBack() = default;
  /// X from words (least significant first); leading zero words are dropped.
  explicit BitsBack(std::vector<std::uint64_t> words);
  /// X from a hexadecimal string ("0x" prefix optional, "0" or "" for zero); throws on a bad digit.
  static BitsBack from_hex(const std::string& hex);
  /// X as lower-case hexadecimal with "0x" (the same text as Python's hex()).
  std::string to_hex() const;

  void push_uniform(std::uint64_t idx, std::uint64_t m);  ///< X = X*m + idx (idx < m, m >= 1)
  std::uint64_t pop_uniform(std::uint64_t m);            ///< idx = X mod m; X = X / m
  /// rANS push: X = (X div f)*2^48 + (X mod f) + c; needs f >= 1 and c + f <= 2^48.
  void push_rans(std::uint64_t c, std::uint64_t f);
  /// rANS pop, the inverse of push_rans(c, f): needs c <= low48() < c + f.
  void pop_rans(std::uint64_t c, std::uint64_t f);
  /// X mod 2^48: the rANS state a pop decodes.
  std::uint64_t low48() const { return words_.empty() ? 0 : (words_[0] & rans_mask); }
  /// The torus shift: the low 48 bits s become (s + g) mod 2^48, the rest of X is kept (g < 2^48).
  void add_low48(std::uint64_t g);
  /// The inverse shift: s becomes (s - g) mod 2^48 (g < 2^48).
  void sub_low48(std::uint64_t g);

  std::size_t bit_length() const;                            ///< bits of X (0 for zero)
  const std::vector<std::uint64_t>& words() const { return words_; }  ///< for snapshots
  bool is_zero() const { return words_.empty(); }            ///< X == 0
  /// Equal values (the word vectors are canonical).
  friend bool operator==(const BitsBack& a, const BitsBack& b) { return a.words_ == b.words_; }

 private:
  void trim();                                       // drop leading zero words
  void mul_add(std::uint64_t m, std::uint64_t a);    // X = X*m + a
  std::uint64_t divmod(std::uint64_t d);             // X = X div d, returns X mod d (d >= 1)
  void set_low48(std::uint64_t s);                   // replace the low 48 bits by s < 2^48
  std::vector<std::uint64_t> words_;
};

}  // namespace revcol::lattice
