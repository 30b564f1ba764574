// A minimal check harness for the C++ tests: every failed CHECK prints its
// location and the test exits non-zero; ctest reads the exit code.
#pragma once

#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace nvib_test {
inline int& failures() {
  static int n = 0;
  return n;
}
inline int& checks() {
  static int n = 0;
  return n;
}
inline int finish(const char* name) {
  std::printf("%s: %d checks, %d failed\n", name, checks(), failures());
  return failures() == 0 ? 0 : 1;
}
}  // namespace nvib_test

#define CHECK(cond)                                                                \
  do {                                                                             \
    ++nvib_test::checks();                                                         \
    if (!(cond)) {                                                                 \
      ++nvib_test::failures();                                                     \
      std::printf("%s:%d: CHECK failed: %s\n", __FILE__, __LINE__, #cond);         \
    }                                                                              \
  } while (0)

#define CHECK_CLOSE(a, b, tol)                                                     \
  do {                                                                             \
    ++nvib_test::checks();                                                         \
    const double va_ = (a), vb_ = (b);                                             \
    if (!(std::abs(va_ - vb_) <= (tol))) {                                         \
      ++nvib_test::failures();                                                     \
      std::printf("%s:%d: CHECK_CLOSE failed: %s = %.17g, %s = %.17g, tol %.3g\n", \
                  __FILE__, __LINE__, #a, va_, #b, vb_, static_cast<double>(tol)); \
    }                                                                              \
  } while (0)
