// Interrupting the long loops of the studies (verify, the paper study, the state-saving study,
// the randomness word stream): a check the caller passes in, called every kEvery iterations.
// The bindings pass one that looks for Ctrl-C (PyErr_CheckSignals, with the GIL taken when the
// loop released it); when it says stop, the loop throws Interrupted, which unwinds to the
// binding, and the binding raises the pending KeyboardInterrupt. A study is a function of its
// configuration, so nothing is left half-done: its result is simply not returned. (The
// engines stop between events instead and stay usable: revcol::engine::Poll.)
#pragma once
#include <cstdint>
#include <exception>
#include <functional>

namespace revcol {

/// Thrown by a long loop when its interrupt check asked it to stop.
struct Interrupted : std::exception {
  /// "interrupted".
  const char* what() const noexcept override { return "interrupted"; }
};

/// The caller's check: returns true to stop (empty: never).
using InterruptCheck = std::function<bool()>;

/// Counts a loop's iterations and calls the check every kEvery of them; throws Interrupted when
/// it says stop. One increment and one compare per tick when nothing is due.
class InterruptPoll {
 public:
  static constexpr std::uint32_t kEvery = 1u << 14;  ///< iterations between checks
  /// Polls `check` (a reference: it must outlive the poll) every `every` ticks.
  explicit InterruptPoll(const InterruptCheck& check, std::uint32_t every = kEvery)
      : check_(check), every_(every > 0 ? every : 1) {}
  /// One iteration.
  void tick() {
    if (++n_ < every_) return;
    n_ = 0;
    now();
  }
  /// Checks at once (between phases).
  void now() const {
    if (check_ && check_()) throw Interrupted{};
  }

 private:
  const InterruptCheck& check_;
  std::uint32_t every_;
  std::uint32_t n_ = 0;
};

}  // namespace revcol
