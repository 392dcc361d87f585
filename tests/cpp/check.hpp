// Minimal test harness for the C++ tests: CHECK records a failure and goes on, REQUIRE
// stops the test; main() returns non-zero when anything failed, which ctest reads.
#pragma once
#include <cmath>
#include <cstdio>
#include <exception>
#include <functional>
#include <string>
#include <vector>

namespace check {
struct Case {
  const char* name;
  std::function<void()> fn;
};
inline std::vector<Case>& cases() {
  static std::vector<Case> all;
  return all;
}
inline int& failures() {
  static int n = 0;
  return n;
}
struct Register {
  Register(const char* name, std::function<void()> fn) { cases().push_back({name, std::move(fn)}); }
};
struct Abort {};
inline void fail(const char* file, int line, const std::string& what) {
  std::fprintf(stderr, "%s:%d: FAILED: %s\n", file, line, what.c_str());
  ++failures();
}
inline int run_all() {
  int failed_cases = 0;
  for (auto& c : cases()) {
    const int before = failures();
    try {
      c.fn();
    } catch (const Abort&) {
    } catch (const std::exception& e) {
      std::fprintf(stderr, "%s: unexpected exception: %s\n", c.name, e.what());
      ++failures();
    }
    const bool ok = failures() == before;
    failed_cases += ok ? 0 : 1;
    std::printf("[%s] %s\n", ok ? "ok  " : "FAIL", c.name);
  }
  std::printf("%zu passed, %d failed\n", cases().size() - failed_cases, failed_cases);
  return failed_cases == 0 ? 0 : 1;
}

/// True when f() throws an exception whose message contains `words` (another message, or none
/// thrown, is printed).
inline bool refused(const std::function<void()>& f, const std::string& words) {
  try {
    f();
  } catch (const std::exception& e) {
    if (std::string(e.what()).find(words) != std::string::npos) return true;
    std::fprintf(stderr, "    unexpected message: %s\n", e.what());
    return false;
  }
  std::fprintf(stderr, "    not refused (wanted '%s')\n", words.c_str());
  return false;
}
}  // namespace check

#define CHECK_CAT2(a, b) a##b
#define CHECK_CAT(a, b) CHECK_CAT2(a, b)
#define TEST_CASE(name)                                                              \
  static void CHECK_CAT(test_fn_, __LINE__)();                                       \
  static check::Register CHECK_CAT(test_reg_, __LINE__)(name, CHECK_CAT(test_fn_, __LINE__)); \
  static void CHECK_CAT(test_fn_, __LINE__)()
// variadic so that a condition with template commas (f<1, 2>(x) == y) needs no parentheses
#define CHECK(...) \
  do { if (!(__VA_ARGS__)) check::fail(__FILE__, __LINE__, #__VA_ARGS__); } while (0)
#define REQUIRE(...) \
  do { if (!(__VA_ARGS__)) { check::fail(__FILE__, __LINE__, #__VA_ARGS__); throw check::Abort{}; } } while (0)
#define CHECK_NEAR(a, b, tol)                                                              \
  do {                                                                                     \
    const double check_a_ = (a), check_b_ = (b);                                           \
    if (!(std::fabs(check_a_ - check_b_) <= (tol)))                                        \
      check::fail(__FILE__, __LINE__, std::string(#a " ~ " #b ": ") + std::to_string(check_a_) + \
                                          " vs " + std::to_string(check_b_));              \
  } while (0)
// The expression must throw an exception of type T.
#define CHECK_THROWS_AS(expr, T)                                                 \
  do {                                                                           \
    bool check_thrown_ = false;                                                  \
    try { (void)(expr); } catch (const T&) { check_thrown_ = true; } catch (...) {} \
    if (!check_thrown_) check::fail(__FILE__, __LINE__, "expected " #T " from " #expr); \
  } while (0)
#define CHECK_MAIN() \
  int main() { return check::run_all(); }
