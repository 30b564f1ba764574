// EffectSet: the declared effects as a force functor for Model.
//
// Every effect it is given acts: with a LinearParts to assemble into, linear
// springs and dampers go into K and C once; without one they are evaluated
// like the rest. Constant loads go into a constant vector; the other effects
// are compiled once into flat terms grouped by law and by how their measures
// are stored (compiled_terms.hpp): one indirect call per group, never per
// effect, and no switch in the loop. A load reads no measure, a spring no velocity.
//
// The force vector is first *written* (constant loads plus the dense loads,
// which need no state) and then accumulated into. Zeroing it first is a
// memset call whose wide stores the effects' narrow read-modify-writes then
// wait on; measured 30% slower on the building scene.
#pragma once

#include <algorithm>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "../core/interrupt.hpp"
#include "../core/mass.hpp"
#include "compiled_terms.hpp"
#include "effect.hpp"
#include "effect_array.hpp"

namespace nvib {
namespace effects {

// Where linear springs and dampers are assembled: their entries (row, column, value), summed into
// sparse K and C by to_matrices() (each empty if nothing went into it).
struct LinearParts {
  std::vector<Eigen::Triplet<double, int>> k, c;

  static SparseMatrix to_matrix(const std::vector<Eigen::Triplet<double, int>>& entries, Index n) {
    if (entries.empty()) return SparseMatrix();
    SparseMatrix A(n, n);
    A.setFromTriplets(entries.begin(), entries.end());  // duplicates summed
    A.prune(0.0);
    A.makeCompressed();
    return A;
  }
};

class EffectSet {
 public:
  EffectSet() = default;
  // `mass` turns ground accelerations' influence vectors r into M r. Effects come one by one (list)
  // and as arrays of one law (arrays).
  EffectSet(std::vector<Effect> list, const Mass& mass, LinearParts* linear = nullptr,
            std::vector<EffectArray> arrays = {})
      : all_(std::move(list)), arrays_(std::move(arrays)) {
    const Index n = mass.size();
    a_.f_const.setZero(n);
    for (size_t q = 0; q < arrays_.size(); ++q) take_array(q, linear);
    for (size_t i = 0; i < all_.size(); ++i) {
      Effect& e = all_[i];
      for (Index d : e.index)
        NVIB_CHECK(d < n, "effects[" + std::to_string(i) + "].measure",
                   "DOF index " + std::to_string(d) + " is out of range for " + std::to_string(n) +
                       " degrees of freedom");
      if (e.law == Law::ground_acceleration) to_mass_weighted(e, mass);
      uses_time_ = uses_time_ || e.uses_time();
      linear_ = linear_ && e.is_linear();
      if (linear && (e.law == Law::spring || e.law == Law::damper)) {
        assemble(e, e.law == Law::spring ? linear->k : linear->c);
        continue;
      }
      if (e.law == Law::constant_force) {
        for (size_t k = 0; k < e.index.size(); ++k) a_.f_const[e.index[k]] -= e.coef[k] * e.p0;
        continue;
      }
      active_.push_back(e);
      active_velocity_ = active_velocity_ || e.uses_velocity();
    }
    compile();
  }

  // Copies re-point the compiled terms at their own signals.
  EffectSet(const EffectSet& o) { *this = o; }
  EffectSet& operator=(const EffectSet& o) {
    if (this == &o) return *this;
    all_ = o.all_;
    active_ = o.active_;
    arrays_ = o.arrays_;
    active_arrays_ = o.active_arrays_;
    a_.f_const = o.a_.f_const;
    uses_time_ = o.uses_time_;
    linear_ = o.linear_;
    active_velocity_ = o.active_velocity_;
    compile();
    return *this;
  }
  // Moving the vectors keeps their buffers, so the compiled pointers stay valid.
  EffectSet(EffectSet&&) noexcept = default;
  EffectSet& operator=(EffectSet&&) noexcept = default;

  const std::vector<Effect>& effects() const { return all_; }
  const std::vector<EffectArray>& arrays() const { return arrays_; }
  const std::vector<Effect>& evaluated() const { return active_; }
  // Effects evaluated each step, single ones and those of arrays.
  size_t num_evaluated() const {
    size_t k = active_.size();
    for (size_t q : active_arrays_) k += arrays_[q].size();
    return k;
  }
  const Vector& constant_load() const { return a_.f_const; }  // -P of the constant loads

  void operator()(const CVecRef& u, const CVecRef& v, double t, VecRef out) const {
    const double* up = u.data();
    const double* vp = v.data();
    double* op = out.data();
    auto g = groups_.begin();
    if (g != groups_.end() && g->writes) {
      g->kernel(a_, *g, up, vp, t, op);  // writes constant loads + its loads
      ++g;
    } else {
      // A stored zero the compiler cannot see through keeps this a plain loop, not memcpy.
      const double* base = a_.f_const.data();
      const double z = opaque_zero_;
      for (Index i = 0; i < a_.n; ++i) op[i] = base[i] + z;
    }
    for (; g != groups_.end(); ++g) g->kernel(a_, *g, up, vp, t, op);
  }
  void tangent(const CVecRef& u, const CVecRef& v, double t, MatRef K, MatRef C) const {
    double *k = K.data(), *c = C.data();
    const Index ld = K.outerStride();
    if (ld == K.rows() && C.outerStride() == ld) {  // contiguous: one fill each
      std::fill_n(k, K.size(), 0.0);
      std::fill_n(c, C.size(), 0.0);
    } else {
      K.setZero();
      C.setZero();
    }
    for (const compiled::Group& g : groups_)
      dispatch(g.law, [&](auto L) { compiled::add_tangents<decltype(L)>(a_, g, u.data(), v.data(), t, k, c, ld); });
  }
  // The tangent entry by entry (sparse models): entries once, values at each state, in the same order.
  void tangent_entries(std::vector<Entry>& K, std::vector<Entry>& C) const {
    for (const compiled::Group& g : groups_)
      dispatch(g.law, [&](auto L) { compiled::tangent_entries<decltype(L)>(a_, g, K, C); });
  }
  void tangent_values(const CVecRef& u, const CVecRef& v, double t, double* K, double* C) const {
    for (const compiled::Group& g : groups_)
      dispatch(g.law, [&](auto L) { compiled::tangent_values<decltype(L)>(a_, g, u.data(), v.data(), t, K, C); });
  }
  // out_i = |constant loads|_i + sum over terms of |g_i f|: the round-off scale of the force.
  void magnitude(const CVecRef& u, const CVecRef& v, double t, VecRef out) const {
    out = a_.f_const.cwiseAbs();
    for (const compiled::Group& g : groups_)
      dispatch(g.law, [&](auto L) {
        for (const compiled::Term* c = g.begin; c != g.end; ++c) {
          const double f = std::abs(decltype(L)::value(c->p, a_.measure(*c, u), a_.measure(*c, v), t));
          for (std::int32_t k = c->first; k < c->last; ++k)
            out[a_.idx[static_cast<size_t>(k)]] += std::abs(a_.coef[static_cast<size_t>(k)]) * f;
        }
      });
  }
  // Flags of the evaluated part (K and C carry the rest).
  bool uses_velocity() const { return active_velocity_; }
  bool uses_time() const { return uses_time_; }
  bool is_linear() const { return linear_; }

  // Energy accounting over the effects evaluated each step and the constant
  // loads; the model adds what K and C carry.
  double potential(const CVecRef& u, double t) const {
    return sum_terms(0.0, [&](auto L, const compiled::Term& c) {
      return decltype(L)::potential(c.p, a_.measure(c, u), t);
    });
  }
  double input_power(const CVecRef& u, const CVecRef& v, double t) const {
    return sum_terms(-a_.f_const.dot(v), [&](auto L, const compiled::Term& c) {
      return effects::input_power<decltype(L)>(c.p, a_.measure(c, u), a_.measure(c, v), t);
    });
  }
  double dissipated_power(const CVecRef& v) const {
    return sum_terms(0.0, [&](auto L, const compiled::Term& c) {
      using Lw = decltype(L);
      if constexpr (is_dissipative<Lw>()) {
        return effects::dissipated_power<Lw>(c.p, a_.measure(c, v));
      } else {
        (void)c;
        return 0.0;
      }
    });
  }

 private:
  // init + sum over groups of the sum over their terms of fn(L, term)
  template <class Fn>
  double sum_terms(double init, Fn&& fn) const {
    double e = init;
    for (const compiled::Group& g : groups_)
      e += dispatch(g.law, [&](auto L) {
        double s = 0.0;
        for (const compiled::Term* c = g.begin; c != g.end; ++c) s += fn(L, *c);
        return s;
      });
    return e;
  }

  // An array: linear springs and dampers into K and C, constant loads into the constant vector,
  // the rest evaluated each step (compiled with the single effects).
  void take_array(size_t q, LinearParts* linear) {
    const EffectArray& e = arrays_[q];
    if (e.size() == 0) return;
    uses_time_ = uses_time_ || e.uses_time();
    linear_ = linear_ && e.is_linear();
    const bool spring = e.law == Law::spring, damper = e.law == Law::damper;
    if (linear && (spring || damper)) {
      auto& out = spring ? linear->k : linear->c;
      out.reserve(out.size() + 4 * e.size());
      for (size_t k = 0; k < e.size(); ++k) {
        const double c = e.value(0, k);
        const int i = e.i[k], j = e.j[k];
        out.emplace_back(i, i, c);
        if (j >= 0) {
          out.emplace_back(j, j, c);
          out.emplace_back(i, j, -c);
          out.emplace_back(j, i, -c);
        }
      }
      return;
    }
    if (e.law == Law::constant_force) {
      for (size_t k = 0; k < e.size(); ++k) {
        a_.f_const[e.i[k]] -= e.value(0, k);
        if (e.j[k] >= 0) a_.f_const[e.j[k]] += e.value(0, k);
      }
      return;
    }
    active_arrays_.push_back(q);
    active_velocity_ = active_velocity_ || e.uses_velocity();
  }

  // A ground acceleration acts as g^T a_g(t) with g = M r.
  static void to_mass_weighted(Effect& e, const Mass& mass) {
    const Index n = mass.size();
    Vector r = Vector::Zero(n), w(n);
    for (size_t k = 0; k < e.index.size(); ++k) r[e.index[k]] += e.coef[k];
    mass.apply(r, w);
    e.index.clear();
    e.coef.clear();
    for (Index d = 0; d < n; ++d)
      if (w[d] != 0.0) {
        e.index.push_back(d);
        e.coef.push_back(w[d]);
      }
  }
  static void assemble(const Effect& e, std::vector<Eigen::Triplet<double, int>>& entries) {
    for (size_t i = 0; i < e.index.size(); ++i)
      for (size_t j = 0; j < e.index.size(); ++j)
        entries.emplace_back(static_cast<int>(e.index[i]), static_cast<int>(e.index[j]),
                             e.p0 * e.coef[i] * e.coef[j]);
  }

  // Flat, grouped form of active_ and of the active arrays (rebuilt on copy: terms point at their signals).
  void compile() {
    using namespace compiled;
    a_.n = a_.f_const.size();
    const Index n = a_.n;
    // One source per evaluated effect: a single effect (array = -1) or element k of an array.
    struct Source {
      std::int32_t array;
      std::uint32_t k;
      Law law;
      Storage storage;
    };
    auto single_storage = [&](const Effect& e) {
      const Index m = static_cast<Index>(e.index.size());
      if (m == 1 && e.coef[0] == 1.0) return unit;
      if (m == 2 && e.coef[0] == 1.0 && e.coef[1] == -1.0 && e.index[0] != e.index[1]) return difference;
      if (m <= 2) return two;
      if (2 * m < n) return sparse;
      return e.is_load() ? dense_first : dense;  // a load's force needs no measure
    };
    std::vector<Source> sources;
    size_t total = active_.size();
    for (size_t q : active_arrays_) total += arrays_[q].size();
    sources.reserve(total);
    for (size_t i = 0; i < active_.size(); ++i)
      sources.push_back({-1, static_cast<std::uint32_t>(i), active_[i].law, single_storage(active_[i])});
    for (size_t q : active_arrays_) {
      const EffectArray& e = arrays_[q];
      for (size_t k = 0; k < e.size(); ++k)
        sources.push_back({static_cast<std::int32_t>(q), static_cast<std::uint32_t>(k), e.law,
                           e.j[k] < 0 ? unit : difference});
    }
    // Dense loads first, then by law and storage: each group is one instantiated loop.
    std::stable_sort(sources.begin(), sources.end(), [](const Source& a, const Source& b) {
      const bool fa = a.storage == dense_first, fb = b.storage == dense_first;
      if (fa != fb) return fa;
      return a.law != b.law ? a.law < b.law : a.storage < b.storage;
    });
    a_.idx.clear();
    a_.coef.clear();
    a_.rows.clear();
    a_.idx.reserve(2 * total);
    a_.coef.reserve(2 * total);
    terms_.clear();
    terms_.reserve(total);
    for (const Source& src : sources) {
      if ((terms_.size() & 0xFFFF) == 0) poll_interrupt();  // large models: every 65536 terms
      Term c;
      c.first = static_cast<std::int32_t>(a_.idx.size());
      if (src.array >= 0) {
        const EffectArray& e = arrays_[static_cast<size_t>(src.array)];
        c.i0 = c.i1 = e.i[src.k];
        c.c0 = 1.0;
        a_.idx.push_back(c.i0);
        a_.coef.push_back(1.0);
        if (e.j[src.k] >= 0) {
          c.i1 = e.j[src.k];
          c.c1 = -1.0;
          a_.idx.push_back(c.i1);
          a_.coef.push_back(-1.0);
        }
        c.last = static_cast<std::int32_t>(a_.idx.size());
        c.p = e.params(src.k);
        terms_.push_back(c);
        continue;
      }
      const Effect& e = active_[src.k];
      a_.idx.insert(a_.idx.end(), e.index.begin(), e.index.end());
      a_.coef.insert(a_.coef.end(), e.coef.begin(), e.coef.end());
      c.last = static_cast<std::int32_t>(a_.idx.size());
      if (!e.index.empty()) {
        c.i0 = c.i1 = e.index[0];
        c.c0 = e.coef[0];
      }
      if (e.index.size() > 1) {
        c.i1 = e.index[1];
        c.c1 = e.coef[1];
      }
      if (src.storage == dense || src.storage == dense_first) {
        c.offset = static_cast<Index>(a_.rows.size());
        a_.rows.resize(a_.rows.size() + static_cast<size_t>(n), 0.0);
        for (size_t k = 0; k < e.index.size(); ++k)
          a_.rows[static_cast<size_t>(c.offset + e.index[k])] += e.coef[k];
      }
      c.p = e.params();
      terms_.push_back(c);
    }
    groups_.clear();
    for (size_t i = 0; i < terms_.size(); ++i) {
      const Law law = sources[i].law;
      const Storage st = sources[i].storage;
      if (groups_.empty() || groups_.back().law != law || groups_.back().storage != st)
        groups_.push_back({law, st, kernel_for(law, st), &terms_[i], &terms_[i], false});
      groups_.back().end = &terms_[i] + 1;
    }
    if (!groups_.empty() && groups_.front().storage == dense_first) groups_.front().writes = true;
  }

  std::vector<Effect> all_, active_;
  std::vector<EffectArray> arrays_;
  std::vector<size_t> active_arrays_;  // the arrays evaluated each step
  compiled::Arrays a_;
  bool uses_time_ = false, linear_ = true, active_velocity_ = false;
  double opaque_zero_ = 0.0;  // see operator()
  std::vector<compiled::Term> terms_;
  std::vector<compiled::Group> groups_;
};

}  // namespace effects
}  // namespace nvib
