// Loops over the entries of a vector, unrolled for the small models.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

#include <Eigen/Core>

#include "compiler.hpp"

namespace nvib {

namespace detail {
inline bool finite(double x) { return std::isfinite(x); }

// Integer tests on the bits of the state, with no floating-point dependency chain: a double is not
// finite exactly when its exponent bits are all ones.
constexpr std::uint64_t kExpBits = 0x7FF0000000000000ull;
constexpr std::uint64_t kExpOne = 0x0010000000000000ull;  // all-ones exponent + this sets bit 63
inline std::uint64_t bits_of(double x) {
  std::uint64_t b;
  std::memcpy(&b, &x, sizeof b);
  return b;
}
// Bit 63 set when some x_i is not finite (a loop the compiler vectorises, SSE2 included: a conjunction
// of comparisons on bools is not).
inline std::uint64_t nonfinite_bits(Eigen::Index n, const double* __restrict x) {
  std::uint64_t bad = 0;
  for (Eigen::Index i = 0; i < n; ++i) bad |= (bits_of(x[i]) & kExpBits) + kExpOne;
  return bad;
}
// m = max(m, |x_i|), finite = false if some x_i is not finite (loops the compiler vectorises: the bits'
// test, and Eigen's maximum).
inline void largest(Eigen::Index n, const double* __restrict x, double& m, bool& finite) {
  finite = finite && !(nonfinite_bits(n, x) >> 63);
  if (n > 0) m = std::max(m, Eigen::Map<const Eigen::VectorXd>(x, n).cwiseAbs().maxCoeff());
}

// body(i) for i = 0 .. n-1. Up to 8 entries the count is a compile-time constant, so the loop is
// unrolled into straight-line (and paired SIMD) code without the trip-count tests, alias checks
// and remainder of a general loop, which on a model of a few DOFs cost more than the arithmetic.
// Same operations in the same order either way.
// flatten: the body is inlined into each loop (left to itself, the inliner gives up on a body used
// in nine loops and calls it entry by entry).
template <int N, class F>
NVIB_FLATTEN inline void unrolled(F& body) {
  for (Eigen::Index i = 0; i < N; ++i) body(i);
}
template <class F>
NVIB_FLATTEN inline void looped(Eigen::Index n, F& body) {
  for (Eigen::Index i = 0; i < n; ++i) body(i);
}
// Inlined where it is called (each call has a body of its own, so nothing is duplicated).
template <class F>
NVIB_ALWAYS_INLINE void for_each_index(Eigen::Index n, F&& body) {
  switch (n) {
    case 1: return unrolled<1>(body);
    case 2: return unrolled<2>(body);
    case 3: return unrolled<3>(body);
    case 4: return unrolled<4>(body);
    case 5: return unrolled<5>(body);
    case 6: return unrolled<6>(body);
    case 7: return unrolled<7>(body);
    case 8: return unrolled<8>(body);
    default: return looped(n, body);
  }
}
}  // namespace detail

}  // namespace nvib
