// The evaluation kernels of effect arrays: one loop per law over the array's
// own index arrays, d_k = x[i_k] - x[j_k] (j_k < 0: the ground), with one set
// of law parameters for the whole array or one per effect. A chain of springs
// then reads 8 bytes of indices per spring and step, where compiled terms
// read 56: at 10^5 DOFs and more the explicit schemes are bound by that
// traffic. Linear springs and dampers of arrays are evaluated here too rather
// than by a matrix product (12 bytes per stored entry, three or four per
// spring); their tangent still reaches the iteration matrices entry by entry.
#pragma once

#include <cstdint>
#include <vector>

#include "../base/types.hpp"
#include "laws.hpp"

namespace nvib {
namespace effects {
namespace arrays {

struct ArrayGroup;
using Kernel = void (*)(const ArrayGroup&, const double*, const double*, double, double*);

// An array as evaluated: its law, its index arrays, its parameters (uniform, or per effect), its kernel.
struct ArrayGroup {
  Law law;
  const std::int32_t* i = nullptr;
  const std::int32_t* j = nullptr;
  size_t size = 0;
  LawParams uniform;
  const LawParams* per = nullptr;  // one per effect, or nullptr: `uniform` for all
  Kernel kernel = nullptr;

  const LawParams& params(size_t k) const { return per ? per[k] : uniform; }
  template <class X>
  double measure(size_t k, const X& x) const {
    return j[k] >= 0 ? x[i[k]] - x[j[k]] : x[i[k]] - 0.0;
  }
};

// out += g_k f_k for every effect: f at i_k, -f at j_k.
template <class L, bool Uniform>
void add_forces(const ArrayGroup& g, const double* u, const double* v, double t, double* out) {
  const std::int32_t *I = g.i, *J = g.j;
  for (size_t k = 0; k < g.size; ++k) {
    const std::int32_t i = I[k], j = J[k];
    const LawParams& p = Uniform ? g.uniform : g.per[k];
    double d = 0.0, dd = 0.0;
    if constexpr (uses_displacement<L>()) d = u[i] - (j >= 0 ? u[j] : 0.0);
    if constexpr (L::uses_velocity) dd = v[i] - (j >= 0 ? v[j] : 0.0);
    const double f = L::value(p, d, dd, t);
    out[i] += f;
    if (j >= 0) out[j] -= f;
  }
}

inline Kernel kernel_for(Law law, bool uniform) {
  return dispatch(law, [&](auto L) -> Kernel {
    using Lw = decltype(L);
    return uniform ? &add_forces<Lw, true> : &add_forces<Lw, false>;
  });
}

// f(k, row, column, g_row g_column) for the tangent entries of effect k, in a fixed order.
template <class F>
void for_each_pair(const ArrayGroup& g, size_t k, F&& f) {
  const int i = g.i[k], j = g.j[k];
  f(i, i, 1.0);
  if (j >= 0) {
    f(i, j, -1.0);
    f(j, i, -1.0);
    f(j, j, 1.0);
  }
}

// The slope of effect k: df/dd (displacement laws) or df/dd' (velocity laws).
template <class L>
double slope(const ArrayGroup& g, size_t k, const double* u, const double* v, double t) {
  if constexpr (L::uses_velocity)
    return L::damping(g.params(k), g.measure(k, v));
  else
    return L::stiffness(g.params(k), g.measure(k, u), t);
}

// K += df/dd g g^T or C += df/dd' g g^T (dense, column-major, leading dimension ld).
template <class L>
void add_tangents(const ArrayGroup& g, const double* u, const double* v, double t, double* K, double* C, Index ld) {
  if constexpr (L::is_load) return;
  double* A = L::uses_velocity ? C : K;
  for (size_t k = 0; k < g.size; ++k) {
    const double s = slope<L>(g, k, u, v, t);
    for_each_pair(g, k, [&](int r, int c, double gg) { A[r + c * ld] += s * gg; });
  }
}

// The sparse tangent's entries, and their values in the same order.
template <class L>
void tangent_entries(const ArrayGroup& g, std::vector<Entry>& K, std::vector<Entry>& C) {
  if constexpr (L::is_load) return;
  std::vector<Entry>& out = L::uses_velocity ? C : K;
  for (size_t k = 0; k < g.size; ++k) for_each_pair(g, k, [&](int r, int c, double) { out.push_back({r, c}); });
}
template <class L>
void tangent_values(const ArrayGroup& g, const double* u, const double* v, double t, double*& K, double*& C) {
  if constexpr (L::is_load) return;
  double*& out = L::uses_velocity ? C : K;
  for (size_t k = 0; k < g.size; ++k) {
    const double s = slope<L>(g, k, u, v, t);
    for_each_pair(g, k, [&](int, int, double gg) { *out++ = s * gg; });
  }
}

// sum over the effects of fn(params, measure of u, measure of v).
template <class Fn>
double sum(const ArrayGroup& g, const double* u, const double* v, Fn&& fn) {
  double s = 0.0;
  for (size_t k = 0; k < g.size; ++k) s += fn(g.params(k), u ? g.measure(k, u) : 0.0, v ? g.measure(k, v) : 0.0);
  return s;
}

}  // namespace arrays
}  // namespace effects
}  // namespace nvib
