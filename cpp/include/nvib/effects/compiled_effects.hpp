// The declared effects, compiled once and never changed after: linear springs
// and dampers assembled into K and C (with a LinearParts to assemble into),
// constant loads into a constant vector, the other effects compiled into flat
// terms grouped by law and by how their measures are stored
// (compiled_terms.hpp). EffectSet (effect_set.hpp) evaluates them; its copies
// share one CompiledEffects, so a model copied into each stepper costs no
// memory for its effects.
#pragma once

#include <algorithm>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "../base/interrupt.hpp"
#include "../model/mass.hpp"
#include "array_kernels.hpp"
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

class CompiledEffects {
 public:
  CompiledEffects() = default;  // no effects
  // `mass` turns ground accelerations' influence vectors r into M r. Effects come one by one (list)
  // and as arrays of one law (arrays).
  CompiledEffects(std::vector<Effect> list, const Mass& mass, LinearParts* linear = nullptr,
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
      if (e.index.empty()) continue;  // a measure that is zero (a ground motion moving no mass) acts on nothing
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
      active_.push_back(i);
      active_velocity_ = active_velocity_ || e.uses_velocity();
    }
    compile();
  }

  CompiledEffects(const CompiledEffects&) = delete;  // the terms point into this object
  CompiledEffects& operator=(const CompiledEffects&) = delete;

  const std::vector<Effect>& effects() const { return all_; }
  const std::vector<EffectArray>& arrays() const { return arrays_; }
  // Effects evaluated each step, single ones and those of arrays.
  size_t num_evaluated() const {
    size_t k = active_.size();
    for (size_t q : active_arrays_) k += arrays_[q].size();
    return k;
  }
  const Vector& constant_load() const { return a_.f_const; }  // -P of the constant loads
  const compiled::Arrays& arrays_of_terms() const { return a_; }
  const std::vector<compiled::Group>& groups() const { return groups_; }
  const std::vector<arrays::ArrayGroup>& array_groups() const { return array_groups_; }
  bool uses_velocity() const { return active_velocity_; }
  bool uses_time() const { return uses_time_; }
  bool is_linear() const { return linear_; }

 private:
  // An array: constant loads into the constant vector, the rest evaluated each step by the array
  // kernels (array_kernels.hpp), linear springs and dampers included.
  void take_array(size_t q, LinearParts*) {
    const EffectArray& e = arrays_[q];
    if (e.size() == 0) return;
    uses_time_ = uses_time_ || e.uses_time();
    linear_ = linear_ && e.is_linear();
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

  // Flat, grouped form of the evaluated effects, single ones and those of arrays.
  void compile() {
    using namespace compiled;
    a_.n = a_.f_const.size();
    a_.no_constant_load = a_.f_const.size() == 0 || a_.f_const.cwiseAbs().maxCoeff() == 0.0;
    const Index n = a_.n;
    // One source per evaluated single effect (the arrays keep their own form, below).
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
      if (m == 0) return sparse;  // (not evaluated: see the constructor)
      if (m <= 2) return two;
      if (2 * m < n) return sparse;
      return e.is_load() ? dense_first : dense;  // a load's force needs no measure
    };
    std::vector<Source> sources;
    const size_t total = active_.size();
    sources.reserve(total);
    for (size_t i : active_)
      sources.push_back({-1, static_cast<std::uint32_t>(i), all_[i].law, single_storage(all_[i])});
    // Dense loads first, then by law and storage: each group is one instantiated loop.
    std::stable_sort(sources.begin(), sources.end(), [](const Source& a, const Source& b) {
      const bool fa = a.storage == dense_first, fb = b.storage == dense_first;
      if (fa != fb) return fa;
      return a.law != b.law ? a.law < b.law : a.storage < b.storage;
    });
    a_.idx.clear();
    a_.coef.clear();
    a_.rows.clear();
    terms_.clear();
    terms_.reserve(total);
    for (const Source& src : sources) {
      if ((terms_.size() & 0xFFFF) == 0) poll_interrupt();  // large models: every 65536 terms
      Term c;
      c.first = static_cast<std::int32_t>(a_.idx.size());
      const Effect& e = all_[src.k];
      if (!e.index.empty()) c.i0 = c.i1 = static_cast<std::int32_t>(e.index[0]);
      if (e.index.size() > 1) c.i1 = static_cast<std::int32_t>(e.index[1]);
      if (src.storage != unit && src.storage != difference) {
        a_.idx.insert(a_.idx.end(), e.index.begin(), e.index.end());
        a_.coef.insert(a_.coef.end(), e.coef.begin(), e.coef.end());
        if (src.storage == two && e.index.size() == 1) {  // "two" always reads two entries: a zero second one
          a_.idx.push_back(e.index[0]);
          a_.coef.push_back(0.0);
        }
      }
      c.last = static_cast<std::int32_t>(a_.idx.size());
      if (src.storage == dense || src.storage == dense_first) {
        c.offset = static_cast<Index>(a_.rows.size());
        a_.rows.resize(a_.rows.size() + static_cast<size_t>(n), 0.0);
        for (size_t k = 0; k < e.index.size(); ++k)
          a_.rows[static_cast<size_t>(c.offset + e.index[k])] += e.coef[k];
      }
      c.p = e.params();
      terms_.push_back(c);
    }
    // The arrays: their own kernels over their own index arrays.
    array_groups_.clear();
    per_params_.clear();
    for (size_t q : active_arrays_) {
      const EffectArray& e = arrays_[q];
      arrays::ArrayGroup g;
      g.law = e.law;
      g.i = e.i.data();
      g.j = e.j.data();
      g.size = e.size();
      bool varying = false;
      for (const auto& v : e.values) varying = varying || v.size() > 1;
      g.uniform = e.params(0);
      if (varying) {
        std::vector<LawParams> per(e.size());
        for (size_t k = 0; k < e.size(); ++k) per[k] = e.params(k);
        per_params_.push_back(std::move(per));
        g.per = per_params_.back().data();
      }
      g.kernel = arrays::kernel_for(e.law, !varying);
      array_groups_.push_back(g);
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

  std::vector<Effect> all_;
  std::vector<size_t> active_;         // the single effects evaluated each step (in all_)
  std::vector<EffectArray> arrays_;
  std::vector<size_t> active_arrays_;  // the arrays evaluated each step
  compiled::Arrays a_;
  bool uses_time_ = false, linear_ = true, active_velocity_ = false;
  std::vector<compiled::Term> terms_;
  std::vector<compiled::Group> groups_;
  std::vector<arrays::ArrayGroup> array_groups_;
  std::vector<std::vector<LawParams>> per_params_;  // arrays whose parameters vary: one set per effect
};

}  // namespace effects
}  // namespace nvib
