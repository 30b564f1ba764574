// The evaluation kernels of the effects: one family for single effects and arrays alike. Effects
// are compiled (compiled_effects.hpp) into groups of one law and one way of storing their
// measures; one loop is instantiated per (law, storage, uniform parameters or not), so there is one
// indirect call per group, never per effect, and no switch inside the loops.
//
// Storages (the order is the order of the groups of single effects):
//   dense_first  dense loads evaluated first; the group's first effect writes the force vector
//   ground       d = x[i]                     (a spring to the ground)
//   pair         d = x[i] - x[j]              (the common spring or damper between two DOFs)
//   two          d = c0 x[i] + c1 x[j]
//   sparse       d = sum of coef x[idx] over the effect's entries
//   dense        a row covering at least half the DOFs
//   mixed        d = x[i] - x[j], j < 0 the ground (arrays)
//
// A law with memory reads each effect's committed state and writes its trial state (a pure trial:
// the committed state never changes here); `trial` may be null where no trial is wanted.
#pragma once

#include <cstdint>
#include <cstring>
#include <vector>

#include "../base/types.hpp"
#include "effect.hpp"

namespace nvib {
namespace effects {
namespace kernels {

enum Storage { dense_first = 0, ground = 1, pair = 2, two = 3, sparse = 4, dense = 5, mixed = 6 };

struct Group;
// out += g^T f for every effect of the group (dense_first: writes the first).
using ForceKernel = void (*)(const Group&, const double* u, const double* v, double t, double* out,
                             const double* committed, double* trial);

// The group's tangent into `out`; returns the sum of x - x over its values (0 unless one is not finite).
using TangentKernel = double (*)(const Group&, const double* u, const double* v, double t, const double* committed,
                                 TangentOut& out);

struct Group {
  LawId law = 0;
  Storage storage = sparse;
  bool uniform = false;  // one set of parameters for every effect
  bool writes = false;   // dense_first: the group's first effect writes the force vector
  bool uses_time = false;  // some effect's force depends on t
  std::size_t size = 0;
  const std::int32_t* i = nullptr;  // ground, pair, two, mixed
  const std::int32_t* j = nullptr;  // pair, two, mixed
  const double* c = nullptr;        // two: c[2k], c[2k + 1]
  const std::int32_t* first = nullptr;  // sparse, dense: the entries of effect k are [first[k], first[k + 1])
  const Index* idx = nullptr;
  const double* coef = nullptr;
  const double* rows = nullptr;  // dense: row k at rows + k n
  const double* row_value = nullptr;  // dense_first: the value of every entry of row k, or NaN (not one)
  Index n = 0;
  const double* constant_load = nullptr;  // dense_first: written with the first load (nullptr: none)
  const void* params = nullptr;           // L::Params[size], or [1] if uniform
  std::size_t state = 0;                  // offset of the first effect's state in the state buffers
  ForceKernel kernel = nullptr;
  TangentKernel tangent = nullptr;  // tangent_add<L>: set with kernel
  // dense_first: the loads' values f_k(t), and where the group's first sits among every dense load's
  void (*load_values)(const Group&, double t, double* f) = nullptr;
  // The same values into f, and the rows they add (add_dense_loads) over all DOFs, in one call.
  void (*load_write)(const Group&, double t, double* f, double* out) = nullptr;
  std::size_t load = 0;
  // How far effect k's DOFs lie from DOF k (-1: anywhere; a dense row), so that the force can be
  // evaluated block by block along the DOFs (EffectSet's streamed evaluation); the sizes of one
  // effect's parameters (0 if uniform) and state, to take a range of the group (range()).
  std::int64_t halo = -1;
  std::size_t params_bytes = 0, state_width = 0;

  // Effects k0 .. k1 - 1 of this group as a group of their own (the same storage, parameters and
  // states, offset).
  Group range(std::size_t k0, std::size_t k1) const {
    Group r = *this;
    r.size = k1 - k0;
    if (i) r.i = i + k0;
    if (j) r.j = j + k0;
    if (c) r.c = c + 2 * k0;
    if (first) r.first = first + k0;
    if (rows) r.rows = rows + static_cast<Index>(k0) * n;
    if (!uniform) r.params = static_cast<const unsigned char*>(params) + k0 * params_bytes;
    r.state = state + k0 * state_width;
    return r;
  }

  template <class L>
  const typename L::Params& params_of(std::size_t k) const {
    return static_cast<const typename L::Params*>(params)[uniform ? 0 : k];
  }
  // Effect k's state in a state buffer (an array of doubles; the law's State is a struct of doubles
  // with nothing else in it, state_width()). Read and written in place, field by field: a copy
  // through memcpy kept the state in memory on the stack, which cost a tenth of a step of the
  // inelastic building.
  template <class L>
  decltype(auto) state_of(const double* buffer, std::size_t k) const {
    if constexpr (law::has_state<L>) {
      return static_cast<const typename L::State&>(
          *reinterpret_cast<const typename L::State*>(buffer + state + k * law::state_width<L>()));
    } else {
      (void)buffer, (void)k;
      return NoState{};
    }
  }
  template <class L>
  void store_state(double* buffer, std::size_t k, const typename L::State& s) const {
    if constexpr (law::has_state<L>) *reinterpret_cast<typename L::State*>(buffer + state + k * law::state_width<L>()) = s;
    (void)buffer, (void)k, (void)s;
  }
  // g . x for effect k, the storage known at compile time.
  template <Storage S, class X>
  double measure_of(std::size_t k, const X& x) const {
    if constexpr (S == ground) return x[i[k]];
    if constexpr (S == pair) return x[i[k]] - x[j[k]];
    if constexpr (S == mixed) return j[k] >= 0 ? x[i[k]] - x[j[k]] : x[i[k]] - 0.0;
    if constexpr (S == two) return c[2 * k] * x[i[k]] + c[2 * k + 1] * x[j[k]];
    if constexpr (S == dense || S == dense_first) {
      const double* w = rows + static_cast<Index>(k) * n;
      double d = 0.0;
      for (Index q = 0; q < n; ++q) d += w[q] * x[q];
      return d;
    }
    double d = 0.0;
    for (std::int32_t e = first[k]; e < first[k + 1]; ++e) d += coef[e] * x[idx[e]];
    return d;
  }
  // ... the storage known at run time.
  template <class X>
  double measure(std::size_t k, const X& x) const {
    switch (storage) {
      case ground: return measure_of<ground>(k, x);
      case pair: return measure_of<pair>(k, x);
      case mixed: return measure_of<mixed>(k, x);
      case two: return measure_of<two>(k, x);
      case dense:
      case dense_first: return measure_of<dense>(k, x);
      case sparse: break;
    }
    return measure_of<sparse>(k, x);
  }
  // fn(dof, g_dof) for every entry of effect k's measure, in a fixed order.
  template <class F>
  void for_each_entry(std::size_t k, F&& fn) const {
    switch (storage) {
      case ground: fn(Index(i[k]), 1.0); return;
      case pair:
        fn(Index(i[k]), 1.0);
        fn(Index(j[k]), -1.0);
        return;
      case mixed:
        fn(Index(i[k]), 1.0);
        if (j[k] >= 0) fn(Index(j[k]), -1.0);
        return;
      case two:
        fn(Index(i[k]), c[2 * k]);
        fn(Index(j[k]), c[2 * k + 1]);
        return;
      default:
        for (std::int32_t e = first[k]; e < first[k + 1]; ++e) fn(idx[e], coef[e]);
    }
  }
};

// d and d' of effect k where the law reads them (0 where it does not).
template <class L, Storage S>
inline void measures_of(const Group& g, std::size_t k, const double* u, const double* v, double& d, double& dd) {
  d = L::uses_displacement ? g.measure_of<S>(k, u) : 0.0;
  dd = L::uses_velocity ? g.measure_of<S>(k, v) : 0.0;
}

// The force of an effect (parameters p) from its committed state at `committed`; with memory and
// Trial, its trial state goes to `trial` (both point at this effect's state).
template <class L, bool Trial>
inline double respond(const typename L::Params& p, double d, double dd, double t, const double* committed,
                      double* trial) {
  if constexpr (law::has_state<L>) {
    using State = typename L::State;  // read and written in place, as Group::state_of() and store_state()
    const auto r = L::trial(p, *reinterpret_cast<const State*>(committed), d, dd, t);
    if constexpr (Trial) *reinterpret_cast<State*>(trial) = r.state;
    (void)trial;
    return r.f;
  } else {
    (void)committed, (void)trial;
    return L::value(p, d, dd, t);
  }
}

// The dense loads (a ground acceleration's M r a_g(t)), in two parts: their values f_k(t), and the
// rows w_k f_k they add, so that the values can be kept while t does not change (the Newton
// iterations of a step evaluate the force several times at one time: EffectSet). The group's first
// effect writes the force vector when the group `writes`, with the constant loads if there are any;
// the others add. A load reads no state, so there is no measure to form and no per-effect test.
template <class L>
void dense_load_values(const Group& g, double t, double* f) {
  for (std::size_t k = 0; k < g.size; ++k) f[k] = L::value(g.params_of<L>(k), 0.0, 0.0, t);
}
// out[q0 .. q1) gets the rows times value(k), k = 0 .. size - 1 in order (value(0) first).
template <class Value>
NVIB_ALWAYS_INLINE void add_rows(const Group& g, Value&& value, double* __restrict out, Index q0, Index q1) {
  std::size_t k = 0;
  const Index n = g.n, m = q1 - q0;
  out += q0;
  // Row k's entry q: w[q], or its one value where it has one (then the row is not read: as exact, one
  // stream less).
  const double* __restrict rv = g.row_value;
  auto one_value = [rv](std::size_t r) { return rv != nullptr && !std::isnan(rv[r]); };
  if (g.writes && g.size > 0) {
    const double f0 = value(std::size_t(0));
    const double* __restrict w = g.rows + q0;
    const double* __restrict base = g.constant_load ? g.constant_load + q0 : nullptr;
    if (one_value(0)) {
      const double w0 = rv[0];
      if (base == nullptr)  // one stream less: no constant vector to read
        detail::for_each_index(m, [=](Index q) { out[q] = w0 * f0; });
      else
        detail::for_each_index(m, [=](Index q) { out[q] = base[q] + w0 * f0; });
    } else if (base == nullptr) {
      detail::for_each_index(m, [=](Index q) { out[q] = w[q] * f0; });
    } else {
      detail::for_each_index(m, [=](Index q) { out[q] = base[q] + w[q] * f0; });
    }
    k = 1;
  }
  for (; k < g.size; ++k) {
    const double fk = value(k);
    if (one_value(k)) {
      const double wk = rv[k];
      for (Index q = 0; q < m; ++q) out[q] += wk * fk;
    } else {
      const double* __restrict w = g.rows + static_cast<Index>(k) * n + q0;
      for (Index q = 0; q < m; ++q) out[q] += w[q] * fk;
    }
  }
}
inline void add_dense_loads(const Group& g, const double* f, double* __restrict out, Index q0, Index q1) {
  add_rows(g, [f](std::size_t k) { return f[k]; }, out, q0, q1);
}
inline void add_dense_loads(const Group& g, const double* f, double* __restrict out) {
  add_dense_loads(g, f, out, 0, g.n);
}
// Each value computed, kept and added where it is used (the explicit schemes' one evaluation per
// time): add_dense_loads' operations in its order.
template <class L>
void dense_load_write(const Group& g, double t, double* __restrict f, double* __restrict out) {
  add_rows(g, [&](std::size_t k) { return f[k] = L::value(g.params_of<L>(k), 0.0, 0.0, t); }, out, 0, g.n);
}
using LoadValues = void (*)(const Group&, double t, double* f);

template <class L, Storage S, bool Uniform>
void add_forces(const Group& g, const double* u, const double* v, double t, double* out, const double* committed,
                double* trial) {
  if constexpr (S == dense_first && L::is_load) {  // only loads are stored dense_first (CompiledEffects)
    for (std::size_t k = 0; k < g.size; ++k) {  // (EffectSet keeps the values instead: load_values)
      Group one = g;
      one.rows = g.rows + static_cast<Index>(k) * g.n;
      one.size = 1;
      one.writes = g.writes && k == 0;
      const double f = L::value(g.params_of<L>(k), 0.0, 0.0, t);
      add_dense_loads(one, &f, out);
    }
    (void)u, (void)v, (void)committed, (void)trial;
    return;
  } else {
    // The group's fields in locals and the arrays declared apart, so that nothing is reloaded after
    // each store into the force vector.
    const std::size_t size = g.size;
    const std::int32_t* __restrict gi = g.i;
    const std::int32_t* __restrict gj = g.j;
    const auto* __restrict P = static_cast<const typename L::Params*>(g.params);
    const double* __restrict up = u;
    const double* __restrict vp = v;
    double* __restrict op = out;
    // This group's states (nothing to offset for a law without memory); one loop with trial states
    // written, one without, so that no effect tests for them.
    constexpr std::size_t W = law::state_width<L>();
    const double* __restrict cs = W > 0 && committed ? committed + g.state : committed;
    double* __restrict ts = W > 0 && trial ? trial + g.state : nullptr;
    auto loop = [&](auto with_trial) {
      constexpr bool T = decltype(with_trial)::value;
      for (std::size_t k = 0; k < size; ++k) {
        const auto& p = P[Uniform ? 0 : k];
        double d = 0.0, dd = 0.0;
        if constexpr (S == ground || S == pair || S == mixed) {
          const std::int32_t i = gi[k], j = S == ground ? -1 : gj[k];
          const bool paired = S == pair || (S == mixed && j >= 0);
          if constexpr (L::uses_displacement) d = paired ? up[i] - up[j] : up[i] - 0.0;
          if constexpr (L::uses_velocity) dd = paired ? vp[i] - vp[j] : vp[i] - 0.0;
          const double f = respond<L, T>(p, d, dd, t, cs + k * W, T ? ts + k * W : nullptr);
          op[i] += f;
          if (paired) op[j] -= f;
        } else {
          measures_of<L, S>(g, k, up, vp, d, dd);
          const double f = respond<L, T>(p, d, dd, t, cs + k * W, T ? ts + k * W : nullptr);
          if constexpr (S == two) {
            if constexpr (std::is_same_v<L, HertzContact>)
              if (f == 0.0) continue;  // an open contact adds nothing
            op[gi[k]] += g.c[2 * k] * f;
            op[gj[k]] += g.c[2 * k + 1] * f;
          } else if constexpr (S == dense) {
            const double* w = g.rows + static_cast<Index>(k) * g.n;
            for (Index q = 0; q < g.n; ++q) op[q] += w[q] * f;
          } else {
            for (std::int32_t e = g.first[k]; e < g.first[k + 1]; ++e) op[g.idx[e]] += g.coef[e] * f;
          }
        }
      }
    };
    if (W > 0 && ts)
      loop(std::true_type{});
    else
      loop(std::false_type{});
  }
}

template <class L>
ForceKernel force_kernel(Storage s, bool uniform) {
  switch (s) {
    case dense_first:
      if constexpr (L::is_load) return &add_forces<L, dense_first, false>;
      break;  // (only loads are stored dense_first)
    case ground: return uniform ? &add_forces<L, ground, true> : &add_forces<L, ground, false>;
    case pair: return uniform ? &add_forces<L, pair, true> : &add_forces<L, pair, false>;
    case mixed: return uniform ? &add_forces<L, mixed, true> : &add_forces<L, mixed, false>;
    case two: return &add_forces<L, two, false>;
    case dense: return &add_forces<L, dense, false>;
    case sparse: break;
  }
  return &add_forces<L, sparse, false>;
}

// A chain of effects along consecutive DOFs (pair or mixed storage with i_k = i_0 + k and j_k = i_k - 1,
// j_0 = -1 allowed: the storeys of a shear building, the links of a chain): DOF i_k
// receives f_k from effect k, then -f_{k+1} from effect k + 1, which the general loop adds through
// memory one effect after the other, each waiting on the store of the one before. Here each DOF's two
// contributions are summed in a register, in that order, and stored once: the same operations in the
// same order, without the chain of stores.
template <class L, bool Uniform>
void add_chain_forces(const Group& g, const double* u, const double* v, double t, double* out, const double* committed,
                      double* trial) {
  const std::size_t size = g.size;
  if (size == 0) return;
  const auto* __restrict P = static_cast<const typename L::Params*>(g.params);
  const double* __restrict up = u;
  const double* __restrict vp = v;
  const std::int32_t i0 = g.i[0];
  double* __restrict op = out + i0;  // op[k]: the DOF of effect k's i side
  constexpr std::size_t W = law::state_width<L>();
  const double* __restrict cs = W > 0 && committed ? committed + g.state : committed;
  double* __restrict ts = W > 0 && trial ? trial + g.state : nullptr;
  const bool grounded = g.j[0] < 0;  // (pair and mixed storage: j is stored)
  // The forces of a chunk of effects into a buffer (a loop without dependences between effects), then
  // each DOF's two contributions, f_k - f_{k+1}, in a second loop; the last force of a chunk is carried.
  constexpr std::size_t kChunk = 256;
  double f[kChunk + 1];
  auto loop = [&](auto with_trial) {
    constexpr bool T = decltype(with_trial)::value;
    auto force = [&](std::size_t k, auto ground) {
      const std::int32_t i = i0 + static_cast<std::int32_t>(k);
      double d = 0.0, dd = 0.0;
      if constexpr (L::uses_displacement) d = decltype(ground)::value ? up[i] - 0.0 : up[i] - up[i - 1];
      if constexpr (L::uses_velocity) dd = decltype(ground)::value ? vp[i] - 0.0 : vp[i] - vp[i - 1];
      return respond<L, T>(P[Uniform ? 0 : k], d, dd, t, cs + k * W, T ? ts + k * W : nullptr);
    };
    f[0] = grounded ? force(0, std::true_type{}) : force(0, std::false_type{});
    if (!grounded) op[-1] -= f[0];
    for (std::size_t c0 = 0; c0 < size; c0 += kChunk) {
      const std::size_t m = std::min(kChunk, size - c0);  // effects c0 .. c0 + m - 1 add to op[c0 ..]
      const std::size_t next = std::min(m, size - 1 - c0);  // the forces after them known in this chunk
      for (std::size_t q = 1; q <= next; ++q) f[q] = force(c0 + q, std::false_type{});
      double* __restrict o = op + c0;
      for (std::size_t q = 0; q < next; ++q) o[q] = o[q] + f[q] - f[q + 1];
      if (next < m) o[m - 1] += f[m - 1];  // the chain's last effect
      f[0] = f[m];
    }
  };
  if (W > 0 && ts)
    loop(std::true_type{});
  else
    loop(std::false_type{});
}

// Whether a group of differences of two DOFs (the first may be to the ground) is a chain along
// consecutive DOFs long enough for add_chain_forces to pay (on a few storeys the chain of stores it
// avoids is short, and its two loops cost more: 197 against 154 instructions on six storeys).
inline bool is_chain(const Group& g) {
  if (!(g.storage == pair || g.storage == mixed) || g.size < 32) return false;
  for (std::size_t k = 0; k < g.size; ++k) {
    if (g.i[k] != g.i[0] + static_cast<std::int64_t>(k)) return false;
    const bool first_grounded = k == 0 && g.j[k] < 0;
    if (!first_grounded && g.j[k] != g.i[k] - 1) return false;
  }
  return true;
}

template <class L>
ForceKernel force_kernel(const Group& g) {
  if (is_chain(g)) return g.uniform ? &add_chain_forces<L, true> : &add_chain_forces<L, false>;
  return force_kernel<L>(g.storage, g.uniform);
}


// (d, d') of effect k, the storage known at run time.
template <class L>
inline void measures(const Group& g, std::size_t k, const double* u, const double* v, double& d, double& dd) {
  d = L::uses_displacement ? g.measure(k, u) : 0.0;
  dd = L::uses_velocity ? g.measure(k, v) : 0.0;
}

// Both slopes of effect k at (u, v, t) from its committed state.
template <class L>
inline Slopes slopes_at(const Group& g, std::size_t k, const double* u, const double* v, double t,
                        const double* committed) {
  double d, dd;
  measures<L>(g, k, u, v, d, dd);
  return law::slopes<L>(g.params_of<L>(k), g.state_of<L>(committed, k), d, dd, t);
}

// K += df/dd g g^T, C += df/dd' g g^T for every effect of the group (K, C column-major with
// leading dimension ld; each where the law reads d or d'). One or two entries are written directly;
// longer measures loop over their list, in its order.
template <class L>
void add_tangents(const Group& g, const double* u, const double* v, double t, double* K, double* C, Index ld,
                  const double* committed) {
  if constexpr (L::is_load) {
    (void)g, (void)u, (void)v, (void)t, (void)K, (void)C, (void)ld, (void)committed;
    return;
  } else {
    auto add = [&](double* A, std::size_t k, double s) {
      switch (g.storage) {
        case ground: A[g.i[k] + g.i[k] * ld] += s; return;
        case pair:
          if (s == 0.0) return;
          A[g.i[k] + g.i[k] * ld] += s;
          A[g.i[k] + g.j[k] * ld] -= s;
          A[g.j[k] + g.i[k] * ld] -= s;
          A[g.j[k] + g.j[k] * ld] += s;
          return;
        case mixed:
          g.for_each_entry(k, [&](Index r, double gr) {
            g.for_each_entry(k, [&](Index c, double gc) { A[r + c * ld] += s * (gr * gc); });
          });
          return;
        default:
          if (s == 0.0) return;
          g.for_each_entry(k, [&](Index r, double gr) {
            g.for_each_entry(k, [&](Index c, double gc) { A[r + c * ld] += s * gr * gc; });
          });
      }
    };
    for (std::size_t k = 0; k < g.size; ++k) {
      const Slopes s = slopes_at<L>(g, k, u, v, t, committed);
      if constexpr (L::uses_displacement) add(K, k, s.kd);
      if constexpr (L::uses_velocity) add(C, k, s.kv);
    }
  }
}

// The entries (row, column) of the tangent of every effect of the group, in the order
// tangent_values() writes them: g_i g_j for i, j over the measure, into K where the law reads d
// and into C where it reads d'; nothing for a load.
template <class L>
void tangent_entries(const Group& g, std::vector<Entry>& K, std::vector<Entry>& C) {
  if constexpr (!L::is_load) {
    auto push = [&](std::vector<Entry>& out) {
      for (std::size_t k = 0; k < g.size; ++k)
        g.for_each_entry(k, [&](Index r, double) {
          g.for_each_entry(k, [&](Index c, double) { out.push_back({static_cast<int>(r), static_cast<int>(c)}); });
        });
    };
    if constexpr (L::uses_displacement) push(K);
    if constexpr (L::uses_velocity) push(C);
  }
  (void)g, (void)K, (void)C;
}

// Their values: df/dd g_i g_j (and df/dd' g_i g_j), advancing K and C past the group's entries.
// The storages of one DOF or a difference of two (every storey spring, every array) with the storage
// known at compile time, as add_forces: the entries written straight, (i, i), (i, j), (j, i), (j, j),
// with g = (1, -1) (the same values as x gi gj, which is exact for gi, gj = +-1).
template <class L, Storage S>
void two_entry_tangent_values(const Group& g, const double* u, const double* v, double t, double*& K, double*& C,
                              const double* committed) {
  for (std::size_t k = 0; k < g.size; ++k) {
    double d, dd;
    measures_of<L, S>(g, k, u, v, d, dd);
    const Slopes s = law::slopes<L>(g.params_of<L>(k), g.state_of<L>(committed, k), d, dd, t);
    const bool paired = S == pair || (S == mixed && g.j[k] >= 0);
    auto write = [&](double*& out, double x) {
      *out++ = x;
      if (paired) {
        *out++ = -x;
        *out++ = -x;
        *out++ = x;
      }
    };
    if constexpr (L::uses_displacement) write(K, s.kd);
    if constexpr (L::uses_velocity) write(C, s.kv);
  }
}
template <class L>
void tangent_values(const Group& g, const double* u, const double* v, double t, double*& K, double*& C,
                    const double* committed) {
  if constexpr (!L::is_load) {
    switch (g.storage) {
      case ground: return two_entry_tangent_values<L, ground>(g, u, v, t, K, C, committed);
      case pair: return two_entry_tangent_values<L, pair>(g, u, v, t, K, C, committed);
      case mixed: return two_entry_tangent_values<L, mixed>(g, u, v, t, K, C, committed);
      default: break;
    }
    for (std::size_t k = 0; k < g.size; ++k) {
      const Slopes s = slopes_at<L>(g, k, u, v, t, committed);
      auto write = [&](double*& out, double x) {
        g.for_each_entry(k, [&](Index, double gi) { g.for_each_entry(k, [&](Index, double gj) { *out++ = x * gi * gj; }); });
      };
      if constexpr (L::uses_displacement) write(K, s.kd);
      if constexpr (L::uses_velocity) write(C, s.kv);
    }
  }
  (void)g, (void)u, (void)v, (void)t, (void)K, (void)C, (void)committed;
}

// tangent_values() and the scatter of its values into the iteration matrix's storage in one pass: each
// value goes to the list (out.K, out.C) and is added at its position (out.tk[*out.pk], ...), entry after
// entry in the list's order, so that every place of the storage sums the same values in the same order as
// a scatter of the finished list would (SparseIterationMatrix::assemble: the same bits).
template <class L, Storage S>
double two_entry_tangent_add(const Group& g, const double* u, const double* v, double t, const double* committed,
                             TangentOut& o) {
  double nonfinite = 0.0;
  double *__restrict K = o.K, *__restrict C = o.C, *__restrict tk = o.tk, *__restrict tc = o.tc;
  const int *__restrict pk = o.pk, *__restrict pc = o.pc;
  for (std::size_t k = 0; k < g.size; ++k) {
    double d, dd;
    measures_of<L, S>(g, k, u, v, d, dd);
    const Slopes s = law::slopes<L>(g.params_of<L>(k), g.state_of<L>(committed, k), d, dd, t);
    const bool paired = S == pair || (S == mixed && g.j[k] >= 0);
    auto put = [&](double* __restrict& list, const int* __restrict& pos, double* __restrict to, double x) {
      nonfinite += x - x;  // (-x is finite where x is)
      list[0] = x;
      to[pos[0]] += x;
      if (paired) {
        list[1] = -x;
        list[2] = -x;
        list[3] = x;
        to[pos[1]] += -x;
        to[pos[2]] += -x;
        to[pos[3]] += x;
        list += 4;
        pos += 4;
      } else {
        list += 1;
        pos += 1;
      }
    };
    if constexpr (L::uses_displacement) put(K, pk, tk, s.kd);
    if constexpr (L::uses_velocity) put(C, pc, tc, s.kv);
  }
  o.K = K, o.C = C, o.pk = pk, o.pc = pc;
  return nonfinite;
}
template <class L>
double tangent_add(const Group& g, const double* u, const double* v, double t, const double* committed, TangentOut& o) {
  if constexpr (L::is_load) {
    (void)g, (void)u, (void)v, (void)t, (void)committed, (void)o;
    return 0.0;
  } else {
    switch (g.storage) {
      case ground: return two_entry_tangent_add<L, ground>(g, u, v, t, committed, o);
      case pair: return two_entry_tangent_add<L, pair>(g, u, v, t, committed, o);
      case mixed: return two_entry_tangent_add<L, mixed>(g, u, v, t, committed, o);
      default: break;
    }
    double *K = o.K, *C = o.C;
    tangent_values<L>(g, u, v, t, K, C, committed);
    return add_listed(o, static_cast<std::size_t>(K - o.K), static_cast<std::size_t>(C - o.C));
  }
}

// kd_r += df/dd g_r g_r for every effect and every entry r of its measure (the diagonal entries of
// tangent_values(), summed by DOF): the diagonal of K_t without its list of entries.
template <class L>
void add_tangent_diagonal(const Group& g, const double* u, const double* v, double t, double* kd, const double* committed) {
  if constexpr (!L::is_load && L::uses_displacement) {
    for (std::size_t k = 0; k < g.size; ++k) {
      const double s = slopes_at<L>(g, k, u, v, t, committed).kd;
      g.for_each_entry(k, [&](Index r, double gr) {
        g.for_each_entry(k, [&](Index c, double gc) {
          if (r == c) kd[r] += s * gr * gc;
        });
      });
    }
  }
  (void)g, (void)u, (void)v, (void)t, (void)kd, (void)committed;
}

// out_i += |g_i f| for every effect: the round-off scale of the force.
template <class L>
void add_magnitude(const Group& g, const double* u, const double* v, double t, double* out, const double* committed) {
  for (std::size_t k = 0; k < g.size; ++k) {
    const double f = std::abs(law::force<L>(g.params_of<L>(k), g.state_of<L>(committed, k), g.measure(k, u),
                                            g.measure(k, v), t));
    if (g.storage == mixed) {
      out[g.i[k]] += f;
      if (g.j[k] >= 0) out[g.j[k]] += f;
    } else {
      g.for_each_entry(k, [&](Index q, double gq) { out[q] += std::abs(gq) * f; });
    }
  }
}

// The sum over the group's effects of fn(params, state, measure of u, measure of v) (u, v may be null).
template <class L, class Fn>
double sum(const Group& g, const double* u, const double* v, const double* committed, Fn&& fn) {
  double s = 0.0;
  for (std::size_t k = 0; k < g.size; ++k)
    s += fn(g.params_of<L>(k), g.state_of<L>(committed, k), u ? g.measure(k, u) : 0.0, v ? g.measure(k, v) : 0.0);
  return s;
}

// Commits each effect's state at (u, v, t): the trial from its committed state, in place.
template <class L>
void commit_at(const Group& g, const double* u, const double* v, double t, double* committed) {
  if constexpr (law::has_state<L>) {
    for (std::size_t k = 0; k < g.size; ++k) {
      double d, dd;
      measures<L>(g, k, u, v, d, dd);
      g.store_state<L>(committed, k, L::trial(g.params_of<L>(k), g.state_of<L>(committed, k), d, dd, t).state);
    }
  }
  (void)g, (void)u, (void)v, (void)t, (void)committed;
}

}  // namespace kernels
}  // namespace effects
}  // namespace nvib
