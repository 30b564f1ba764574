// Loops over the entries of a vector, unrolled for the small models.
#pragma once

#include <Eigen/Core>

#include "compiler.hpp"

namespace nvib {

namespace detail {
inline bool finite(double x) { return std::isfinite(x); }

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
