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
//
// Storage: up to four words inline, more on the heap; the value is the same either way
// (equality compares values). The engine holds one X per particle, about 128 bits that move by
// a bit or two per collision; within a collision the pushes take it to about 210 bits before the
// pops bring it back, so four words keep every step off the heap (test_lattice_local).
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

  BitsBack() noexcept {}
  /// X from words (least significant first); leading zero words are dropped.
  explicit BitsBack(const std::vector<std::uint64_t>& words);
  BitsBack(const BitsBack& o) {  // (inline: the journals copy an X per particle and event)
    if (o.n_ <= kInline) {
      n_ = o.n_;
      const std::uint64_t* w = o.data();
      for (std::uint32_t k = 0; k < n_; ++k) inl_[k] = w[k];
    } else {
      copy_words(o);
    }
  }
  BitsBack(BitsBack&& o) noexcept;
  BitsBack& operator=(const BitsBack& o) {
    if (this != &o) {
      if (o.n_ <= cap_) {
        n_ = o.n_;
        std::uint64_t* d = data();
        const std::uint64_t* w = o.data();
        for (std::uint32_t k = 0; k < n_; ++k) d[k] = w[k];
      } else {
        n_ = 0;
        copy_words(o);
      }
    }
    return *this;
  }
  BitsBack& operator=(BitsBack&& o) noexcept;
  ~BitsBack() { release(); }
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
  std::uint64_t low48() const { return n_ == 0 ? 0 : (data()[0] & rans_mask); }
  /// The torus shift: the low 48 bits s become (s + g) mod 2^48, the rest of X is kept (g < 2^48).
  void add_low48(std::uint64_t g);
  /// The inverse shift: s becomes (s - g) mod 2^48 (g < 2^48).
  void sub_low48(std::uint64_t g);

  std::size_t bit_length() const;                            ///< bits of X (0 for zero)
  std::vector<std::uint64_t> words() const { return {data(), data() + n_}; }  ///< for snapshots
  std::size_t size() const noexcept { return n_; }           ///< words held (no leading zero word)
  bool is_zero() const { return n_ == 0; }                   ///< X == 0
  /// Bytes on the heap (0 while X fits inline).
  std::size_t heap_bytes() const noexcept { return cap_ > kInline ? cap_ * sizeof(std::uint64_t) : 0; }
  /// Equal values (the words are canonical).
  friend bool operator==(const BitsBack& a, const BitsBack& b) noexcept;

 private:
  static constexpr std::uint32_t kInline = 4;
  std::uint64_t* data() noexcept { return cap_ > kInline ? heap_ : inl_; }
  const std::uint64_t* data() const noexcept { return cap_ > kInline ? heap_ : inl_; }
  void push_word(std::uint64_t w) {                  // append a most significant word
    if (n_ < cap_) data()[n_++] = w;
    else grow_push(w);
  }
  void grow_push(std::uint64_t w);                   // push_word when the storage is full
  void copy_words(const BitsBack& o);                // append o's words (this holds none)
  void release() noexcept;                           // free the heap words (if any)
  void steal(BitsBack& o) noexcept;                  // take o's words (o left zero)
  void trim() noexcept {                             // drop leading zero words
    const std::uint64_t* w = data();
    while (n_ > 0 && w[n_ - 1] == 0) --n_;
  }
  void mul_add(std::uint64_t m, std::uint64_t a);    // X = X*m + a (m >= 1: stays canonical)
  std::uint64_t divmod(std::uint64_t d) noexcept;    // X = X div d, returns X mod d (d >= 1)
  void set_low48(std::uint64_t s);                   // replace the low 48 bits by s < 2^48
  std::uint32_t n_ = 0, cap_ = kInline;              // words held; capacity (kInline: inline)
  union {
    std::uint64_t inl_[kInline];
    std::uint64_t* heap_;
  };
};

}  // namespace revcol::lattice
