// A software prefetch the compiler keeps.
#pragma once

namespace revcol::engine {

/// Starts loading the cache line holding p into the cache: a hint, with no effect on any
/// result (an address past an array is not read and does not fault). An asm statement, not
/// __builtin_prefetch: GCC 12 at -O3 deletes a loop of __builtin_prefetch calls whose
/// addresses come through a lambda's by-reference capture (the event loop's prefetch of the
/// next tops vanished so, session 28); an asm volatile statement stays where it is written.
inline void prefetch(const void* p) {
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
  asm volatile("prefetcht0 %0" : : "m"(*static_cast<const char*>(p)));
#else
  __builtin_prefetch(p);
#endif
}

}  // namespace revcol::engine
