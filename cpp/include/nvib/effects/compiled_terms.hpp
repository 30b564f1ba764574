// The evaluation kernels of EffectSet: effects compiled into flat terms,
// grouped by law and by how their measures are stored, one loop instantiated
// per (law, storage) pair.
#pragma once

#include <cstdint>
#include <vector>

#include "../base/types.hpp"
#include "laws.hpp"

namespace nvib {
namespace effects {
namespace compiled {

// unit: d = u_i0 (coefficient 1); difference: d = u_i0 - u_i1 (the common
// spring or damper between two DOFs); two: any two coefficients; sparse: a
// list; dense: a row covering at least half the DOFs; dense_first: dense
// loads, evaluated first, whose first term writes the force vector.
enum Storage { dense_first = 0, unit = 1, difference = 2, two = 3, sparse = 4, dense = 5 };

// One evaluated effect. Its measure's DOFs are kept inline for the unit
// (d = u_i0) and difference (d = u_i0 - u_i1) storages, which store nothing
// else; the others keep their entries in idx/coef[first, last) (two: i0 and i1
// inline too), and a dense one (at least half the DOFs) its row in
// rows[offset, offset + n). 56 bytes: a million springs take 56 MB.
struct Term {
  std::int32_t first = 0, last = 0;
  std::int32_t i0 = 0, i1 = 0;
  Index offset = 0;
  LawParams p;
};

// The flat arrays the terms point into.
struct Arrays {
  Index n = 0;
  std::vector<Index> idx;
  std::vector<double> coef, rows;  // rows: the dense measures
  Vector f_const;  // -P of the constant loads
  bool no_constant_load = false;  // f_const is all zero

  // g . x for storage S.
  template <Storage S, class X>
  double measure_of(const Term& c, const X& x) const {
    if constexpr (S == unit) return x[c.i0];
    if constexpr (S == difference) return x[c.i0] - x[c.i1];
    if constexpr (S == two) return coef[static_cast<size_t>(c.first)] * x[c.i0] + coef[static_cast<size_t>(c.first) + 1] * x[c.i1];
    if constexpr (S == dense || S == dense_first) {
      const double* w = rows.data() + c.offset;
      double d = 0.0;
      for (Index i = 0; i < n; ++i) d += w[i] * x[i];
      return d;
    }
    double d = 0.0;
    for (std::int32_t k = c.first; k < c.last; ++k) d += coef[static_cast<size_t>(k)] * x[idx[static_cast<size_t>(k)]];
    return d;
  }
  // g . x for a storage known at run time.
  template <class X>
  double measure(Storage s, const Term& c, const X& x) const {
    switch (s) {
      case unit: return measure_of<unit>(c, x);
      case difference: return measure_of<difference>(c, x);
      case two: return measure_of<two>(c, x);
      case dense:
      case dense_first: return measure_of<dense>(c, x);
      case sparse: break;
    }
    return measure_of<sparse>(c, x);
  }
  // f(dof, g_dof) for every entry of the measure.
  template <class F>
  void for_each_entry(Storage s, const Term& c, F&& f) const {
    if (s == unit) {
      f(Index(c.i0), 1.0);
    } else if (s == difference) {
      f(Index(c.i0), 1.0);
      f(Index(c.i1), -1.0);
    } else {
      for (std::int32_t k = c.first; k < c.last; ++k) f(idx[static_cast<size_t>(k)], coef[static_cast<size_t>(k)]);
    }
  }
};

// Consecutive terms with the same law and storage; kernel is add_forces<law, storage>.
// writes: the first group, dense_first: its first term writes the force vector.
struct Group;
using Kernel = void (*)(const Arrays&, const Group&, const double*, const double*, double, double*);
struct Group {
  Law law;
  Storage storage;
  Kernel kernel;
  const Term *begin, *end;
  bool writes;
};

// The dense loads (a ground acceleration's M r a_g(t)): the group's first term writes the force vector
// when the group `writes`, with the constant loads if there are any; the others add. A load reads no
// state, so there is no measure to form and no per-term test in the loops.
template <class L>
void add_dense_loads(const Arrays& a, const Group& g, double t, double* __restrict out) {
  const Term* c = g.begin;
  const Index n = a.n;
  if (g.writes && c != g.end) {
    const double f = L::value(c->p, 0.0, 0.0, t);
    const double* __restrict w = a.rows.data() + c->offset;
    if (a.no_constant_load) {  // one stream less: no constant vector to read
      detail::for_each_index(n, [=](Index i) { out[i] = w[i] * f; });
    } else {
      const double* __restrict base = a.f_const.data();
      detail::for_each_index(n, [=](Index i) { out[i] = base[i] + w[i] * f; });
    }
    ++c;
  }
  for (; c != g.end; ++c) {
    const double f = L::value(c->p, 0.0, 0.0, t);
    const double* __restrict w = a.rows.data() + c->offset;
    for (Index i = 0; i < n; ++i) out[i] += w[i] * f;
  }
}

// out += g^T f for every term of the group (the dense loads: add_dense_loads).
template <class L, Storage S>
void add_forces(const Arrays& a, const Group& g, const double* u, const double* v, double t, double* out) {
  if constexpr (S == dense_first) {  // only loads are stored dense_first (CompiledEffects::compile)
    add_dense_loads<L>(a, g, t, out);
    return;
  }
  for (const Term* c = g.begin; c != g.end; ++c) {
    const double d = uses_displacement<L>() ? a.measure_of<S>(*c, u) : 0.0;
    const double dd = L::uses_velocity ? a.measure_of<S>(*c, v) : 0.0;
    const double f = L::value(c->p, d, dd, t);
    if constexpr (S == unit) {
      out[c->i0] += f;
    } else if constexpr (S == difference) {
      out[c->i0] += f;
      out[c->i1] -= f;
    } else if constexpr (S == two) {
      if constexpr (L::id == Law::hertz_contact)
        if (f == 0.0) continue;  // an open contact adds nothing
      out[c->i0] += a.coef[static_cast<size_t>(c->first)] * f;
      out[c->i1] += a.coef[static_cast<size_t>(c->first) + 1] * f;
    } else if constexpr (S == dense) {
      const double* w = a.rows.data() + c->offset;
      for (Index i = 0; i < a.n; ++i) out[i] += w[i] * f;
    } else {
      const Index* idx = a.idx.data();
      const double* coef = a.coef.data();
      for (std::int32_t k = c->first; k < c->last; ++k) out[idx[k]] += coef[k] * f;
    }
  }
}

inline Kernel kernel_for(Law law, Storage s) {
  return dispatch(law, [&](auto L) -> Kernel {
    using Lw = decltype(L);
    switch (s) {
      case dense_first: return &add_forces<Lw, dense_first>;
      case unit: return &add_forces<Lw, unit>;
      case difference: return &add_forces<Lw, difference>;
      case two: return &add_forces<Lw, two>;
      case dense: return &add_forces<Lw, dense>;
      case sparse: break;
    }
    return &add_forces<Lw, sparse>;
  });
}

// K += df/dd g g^T, C += df/dd' g g^T for every term of the group (K, C
// column-major with leading dimension ld). One or two entries are written
// directly; longer measures loop over their list, in its order.
template <class L>
void add_tangents(const Arrays& a, const Group& g, const double* u, const double* v, double t, double* K, double* C,
                  Index ld) {
  if constexpr (L::is_load) return;  // loads do not depend on the state
  double* A = L::uses_velocity ? C : K;
  const double* x = L::uses_velocity ? v : u;
  auto slope = [&](const Term& c, double d) {
    if constexpr (L::uses_velocity)
      return L::damping(c.p, d);
    else
      return L::stiffness(c.p, d, t);
  };
  for (const Term* c = g.begin; c != g.end; ++c) {
    if (g.storage == unit) {
      A[c->i0 + c->i0 * ld] += slope(*c, x[c->i0]);
    } else if (g.storage == difference) {
      const double s = slope(*c, x[c->i0] - x[c->i1]);
      if (s == 0.0) continue;
      A[c->i0 + c->i0 * ld] += s;
      A[c->i0 + c->i1 * ld] -= s;
      A[c->i1 + c->i0 * ld] -= s;
      A[c->i1 + c->i1 * ld] += s;
    } else {
      const double s = slope(*c, a.measure(g.storage, *c, x));
      if (s == 0.0) continue;
      for (std::int32_t i = c->first; i < c->last; ++i)
        for (std::int32_t j = c->first; j < c->last; ++j)
          A[a.idx[static_cast<size_t>(i)] + a.idx[static_cast<size_t>(j)] * ld] +=
              s * a.coef[static_cast<size_t>(i)] * a.coef[static_cast<size_t>(j)];
    }
  }
}

// The entries (row, column) of the tangent of every term of the group, in the order
// tangent_values() writes them: g_i g_j for i, j over the measure, into K (displacement laws) or C
// (velocity laws); nothing for a load.
template <class L>
void tangent_entries(const Arrays& a, const Group& g, std::vector<Entry>& K, std::vector<Entry>& C) {
  if constexpr (L::is_load) return;
  std::vector<Entry>& out = L::uses_velocity ? C : K;
  for (const Term* c = g.begin; c != g.end; ++c)
    a.for_each_entry(g.storage, *c, [&](Index i, double) {
      a.for_each_entry(g.storage, *c, [&](Index j, double) { out.push_back({static_cast<int>(i), static_cast<int>(j)}); });
    });
}

// Their values: df/dd g_i g_j (or df/dd'), advancing K or C past the group's entries.
template <class L>
void tangent_values(const Arrays& a, const Group& g, const double* u, const double* v, double t, double*& K,
                    double*& C) {
  if constexpr (L::is_load) return;
  double*& out = L::uses_velocity ? C : K;
  const double* x = L::uses_velocity ? v : u;
  for (const Term* c = g.begin; c != g.end; ++c) {
    double s;
    if constexpr (L::uses_velocity)
      s = L::damping(c->p, a.measure(g.storage, *c, x));
    else
      s = L::stiffness(c->p, a.measure(g.storage, *c, x), t);
    a.for_each_entry(g.storage, *c, [&](Index, double gi) {
      a.for_each_entry(g.storage, *c, [&](Index, double gj) { *out++ = s * gi * gj; });
    });
  }
}

}  // namespace compiled
}  // namespace effects
}  // namespace nvib
