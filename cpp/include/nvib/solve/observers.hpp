// The observers of the loop (solve.hpp): what a run does with its accepted steps besides stepping.
// Each sees the stepper after every accepted step, may stop the run (a Failure), and writes the
// saved states into the Result; the loop only steps, checks for divergence and polls.
//   SavedHistory   t, u, v, a of the chosen DOFs at the saved steps
//   EnergyAccount  kinetic, potential, work in, viscous and hysteretic dissipation and the balance
//                  error, the powers integrated every step by the trapezoidal rule; the energy check
//   EffectRecorder named effects: measure, rate, force and internal variables at the saved steps
//   CollapseWatch  a law that lost its strength, or an effect with memory deformed beyond a limit
//   PeakTracker    max |u_i| and max |D u| (named measures) over every accepted step, saved or not
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "../base/types.hpp"
#include "../effects/effect_set.hpp"
#include "options.hpp"

namespace nvib {

// The declared effects of a model's force, if it has them (EffectSet, or effects plus a functor).
template <class F, class = void>
struct has_effect_set : std::false_type {};
template <class F>
struct has_effect_set<F, std::void_t<decltype(std::declval<const F&>().effects().select(std::string()))>>
    : std::true_type {};
template <class F>
const effects::EffectSet* effect_set_of(const F& f) {
  if constexpr (std::is_same_v<F, effects::EffectSet>) return &f;
  if constexpr (has_effect_set<F>::value) return &f.effects();
  (void)f;
  return nullptr;
}

namespace observe {

class SavedHistory {
 public:
  SavedHistory(Result& res, const SolveOptions& opt, Index n, std::int64_t nsave) : res_(res), all_(opt.dofs.empty()) {
    if (all_) {
      res.dofs.resize(static_cast<size_t>(n));
      for (Index i = 0; i < n; ++i) res.dofs[static_cast<size_t>(i)] = i;
    } else {
      res.dofs = opt.dofs;
    }
    m_ = static_cast<Index>(res.dofs.size());
    res.t.resize(nsave);
    res.u.resize(nsave, m_);
    res.v.resize(nsave, m_);
    res.a.resize(nsave, m_);
  }
  template <class Stepper>
  void save(const Stepper& st, Index row) {
    res_.t[row] = st.time();
    double* pu = res_.u.data() + row * m_;  // rows are contiguous (row-major)
    double* pv = res_.v.data() + row * m_;
    double* pa = res_.a.data() + row * m_;
    const double *su = st.u().data(), *sv = st.v().data(), *sa = st.a().data();
    if (all_) {
      for (Index j = 0; j < m_; ++j) {
        pu[j] = su[j];
        pv[j] = sv[j];
        pa[j] = sa[j];
      }
    } else {
      for (Index j = 0; j < m_; ++j) {
        const Index d = res_.dofs[static_cast<size_t>(j)];
        pu[j] = su[d];
        pv[j] = sv[d];
        pa[j] = sa[d];
      }
    }
  }
  void resize(Index rows) {
    res_.t.conservativeResize(rows);
    res_.u.conservativeResize(rows, m_);
    res_.v.conservativeResize(rows, m_);
    res_.a.conservativeResize(rows, m_);
  }

 private:
  Result& res_;
  bool all_;
  Index m_ = 0;
};

template <class Stepper>
Failure energy_failure(const Stepper& st, std::int64_t step, double balance, double scale, double limit) {
  Failure f;
  f.status = Status::diverged;
  f.step = step;
  f.t = st.time();
  f.message = "diverged at t = " + detail::fmt(f.t) + " (step " + std::to_string(step) +
              "): the energy balance error " + detail::fmt(balance) + " is " + detail::fmt(std::abs(balance) / scale) +
              " of the energy scale " + detail::fmt(scale) + ", beyond max_energy_error = " + detail::fmt(limit) +
              ": the scheme created or destroyed that energy (unstable, or the step is far too coarse)";
  return f;
}

// Energy accounting: kinetic and potential energy (the stored energy of the laws with memory
// included) at each state; the work of the loads and the viscous dissipation integrated every step
// by the trapezoidal rule; the hysteretic dissipation from the laws' states; the balance error
// kinetic + potential + dissipated + hysteretic - work in - (kinetic + potential at t0). The check
// (a balance error beyond a fraction of the energy scale stops the run as diverged) runs every step
// from the 10th on.
template <class Model>
class EnergyAccount {
 public:
  // track: the relative balance error over every step (saved or not) into Result::peak_energy_error.
  EnergyAccount(Result& res, Model& model, std::int64_t nsave, double limit, double h, bool track = false)
      : res_(res), model_(model), limit_(limit), h_(h), check_(limit < std::numeric_limits<double>::infinity()),
        track_(track) {
    res.energy.resize(nsave, kEnergyColumns);
  }
  template <class Stepper>
  void start(const Stepper& st) {
    sided_ = model_.power_jumps();  // else one input power serves both sides of a step point
    p_in_ = model_.input_power(st.u(), st.v(), st.time(), +1);
    p_diss_ = model_.dissipated_power(st.v());
    hyst0_ = model_.hysteretic_dissipation();
    const double ek = model_.kinetic(st.v()), ep = model_.potential(st.u(), st.time());
    e0_ = ek + ep;
    escale_ = std::abs(ek) + std::abs(ep);
    if (track_) {
      energies(st);
      track();
    }
  }
  // After accepted step i: false (with the failure) when the balance check stops the run.
  template <class Stepper>
  bool step(const Stepper& st, std::int64_t i, Failure& failure) {
    // the input power as this step ends and as the next starts: they differ where a signal's rate jumps
    const double q_in = model_.input_power(st.u(), st.v(), st.time(), -1), q_diss = model_.dissipated_power(st.v());
    work_ += 0.5 * h_ * (p_in_ + q_in);
    diss_ += 0.5 * h_ * (p_diss_ + q_diss);
    p_in_ = sided_ ? model_.input_power(st.u(), st.v(), st.time(), +1) : q_in;
    p_diss_ = q_diss;
    have_ = false;
    // From the 10th step: a run forced from rest starts with a tiny energy of which the start-up
    // balance error is a large fraction (about 1/n^2: 0.9 at step 1, 0.005 at step 10 on the
    // building); an unstable run stays near 1.
    if (check_ && i >= kEnergyCheckFrom) {
      energies(st);
      escale_ = std::max(escale_, std::abs(ek_) + std::abs(ep_) + std::abs(work_) + std::abs(diss_) + std::abs(hyst_));
      const double balance = ek_ + ep_ + diss_ + hyst_ - work_ - e0_;
      if (std::abs(balance) > limit_ * escale_) {
        failure = energy_failure(st, i, balance, escale_, limit_);
        return false;
      }
    }
    if (track_) {
      if (!have_) energies(st);
      track();
    }
    return true;
  }
  template <class Stepper>
  void save(const Stepper& st, Index row) {
    if (!have_) energies(st);  // the check may have computed them for this state already
    res_.energy(row, kinetic) = ek_;
    res_.energy(row, potential) = ep_;
    res_.energy(row, work_in) = work_;
    res_.energy(row, dissipated) = diss_;
    res_.energy(row, hysteretic) = hyst_;
    res_.energy(row, balance_error) = ek_ + ep_ + diss_ + hyst_ - work_ - e0_;
  }
  void resize(Index rows) { res_.energy.conservativeResize(rows, kEnergyColumns); }
  // The length of the next step (adaptive runs): the powers are integrated over it.
  void set_dt(double h) { h_ = h; }

 private:
  template <class Stepper>
  void energies(const Stepper& st) {
    ek_ = model_.kinetic(st.v());
    ep_ = model_.potential(st.u(), st.time());
    hyst_ = model_.hysteretic_dissipation() - hyst0_;
    have_ = true;
  }

  // The relative balance error so far, as relative_balance_error() of a history saved every step: the largest
  // |balance error| over the largest |kinetic| + |potential| + |work in| + |dissipated| + |hysteretic|.
  void track() {
    const double parts = std::abs(ek_) + std::abs(ep_) + std::abs(work_) + std::abs(diss_) + std::abs(hyst_);
    const double balance = ek_ + ep_ + diss_ + hyst_ - work_ - e0_;
    if (!std::isfinite(parts) || !std::isfinite(balance)) blown_ = true;
    worst_ = std::max(worst_, std::abs(balance));
    parts_ = std::max(parts_, parts);
    res_.peak_energy_error = blown_ ? std::numeric_limits<double>::infinity() : (parts_ > 0.0 ? worst_ / parts_ : 0.0);
  }

  Result& res_;
  Model& model_;
  double limit_, h_;
  bool check_, track_, sided_ = false, have_ = false, blown_ = false;
  double worst_ = 0.0, parts_ = 0.0;
  // powers at the last state, integrals so far, the initial total and the scale
  double p_in_ = 0.0, p_diss_ = 0.0, work_ = 0.0, diss_ = 0.0, e0_ = 0.0, escale_ = 0.0, hyst0_ = 0.0;
  double ek_ = 0.0, ep_ = 0.0, hyst_ = 0.0;  // of the current state, when have_
};

// Named effects at the saved steps.
class EffectRecorder {
 public:
  EffectRecorder(Result& res, const effects::EffectSet& set, const std::vector<std::string>& names, std::int64_t nsave)
      : res_(res), set_(set) {
    for (const std::string& name : names) {
      for (const auto& s : selections_)
        NVIB_CHECK(s.name != name, "record", "'" + name + "' is asked for twice");
      selections_.push_back(set.select(name));
      const auto& sel = selections_.back();
      EffectRecord r;
      r.name = name;
      r.type = effects::key_of(sel.law);
      effects::dispatch(sel.law, [&](auto L) {
        for (const char* s : decltype(L)::state_names) r.state_names.emplace_back(s);
      });
      r.count = static_cast<Index>(sel.count);
      r.measure.resize(nsave, r.count);
      r.rate.resize(nsave, r.count);
      r.force.resize(nsave, r.count);
      r.state.resize(nsave, r.count * static_cast<Index>(sel.width));
      res.effects.push_back(std::move(r));
    }
  }
  // Bytes per saved state.
  static double bytes_per_state(const effects::EffectSet& set, const std::vector<std::string>& names) {
    double b = 0.0;
    for (const std::string& name : names) {
      const auto sel = set.select(name);
      b += 8.0 * static_cast<double>(sel.count) * (3.0 + static_cast<double>(sel.width));
    }
    return b;
  }
  template <class Stepper>
  void save(const Stepper& st, Index row) {
    for (size_t q = 0; q < selections_.size(); ++q) {
      EffectRecord& r = res_.effects[q];
      set_.sample(selections_[q], st.u().data(), st.v().data(), st.time(), r.measure.data() + row * r.count,
                  r.rate.data() + row * r.count, r.force.data() + row * r.count, r.state.data() + row * r.state.cols());
    }
  }
  void resize(Index rows) {
    for (EffectRecord& r : res_.effects) {
      r.measure.conservativeResize(rows, r.count);
      r.rate.conservativeResize(rows, r.count);
      r.force.conservativeResize(rows, r.count);
      r.state.conservativeResize(rows, r.state.cols());
    }
  }

 private:
  Result& res_;
  const effects::EffectSet& set_;
  std::vector<effects::EffectSet::Selection> selections_;
};

// Collapse: a law with memory that failed (its strength gone), or an effect with memory deformed
// beyond the limit; the run stops with status collapsed, naming the effect.
class CollapseWatch {
 public:
  CollapseWatch(const effects::EffectSet& set, double limit) : set_(set), limit_(limit), fails_(set.can_fail()) {}
  bool active() const { return fails_ || !std::isnan(limit_); }
  template <class Stepper>
  bool step(const Stepper& st, std::int64_t i, Failure& failure) {
    std::string who;
    double d = 0.0;
    if (fails_ && set_.failed(who)) {
      failure = collapse(st, i, who + " lost its strength");
    } else if (!std::isnan(limit_) && set_.beyond(st.u().data(), limit_, who, d)) {
      failure = collapse(st, i, who + " deformed to " + detail::fmt(d) + ", beyond the collapse limit " + detail::fmt(limit_));
    } else {
      return true;
    }
    return false;
  }

 private:
  template <class Stepper>
  static Failure collapse(const Stepper& st, std::int64_t i, const std::string& what) {
    Failure f;
    f.status = Status::collapsed;
    f.step = i;
    f.t = st.time();
    f.message = "collapsed at t = " + detail::fmt(f.t) + " (step " + std::to_string(i) + "): " + what;
    return f;
  }
  const effects::EffectSet& set_;
  double limit_;
  bool fails_;
};

// The peaks of a run over every accepted step (SolveOptions::peaks): a summary that needs no history.
class PeakTracker {
 public:
  PeakTracker(Result& res, const SolveOptions& opt, Index n) : res_(res), D_(opt.peak_measures) {
    NVIB_CHECK(D_.rows() == 0 || D_.cols() == n, "peak_measures",
               "expected " + std::to_string(n) + " columns (one per DOF), got " + std::to_string(D_.cols()));
    res.peak_u = Vector::Zero(n);
    res.peak_measures = Vector::Zero(D_.rows());
    d_.resize(D_.rows());
  }
  template <class Stepper>
  void update(const Stepper& st) {
    const Vector& u = st.u();
    res_.peak_u = res_.peak_u.cwiseMax(u.cwiseAbs());
    if (D_.rows() > 0) {
      d_.noalias() = D_ * u;
      res_.peak_measures = res_.peak_measures.cwiseMax(d_.cwiseAbs());
    }
  }

 private:
  Result& res_;
  const SparseMatrix& D_;
  Vector d_;
};

}  // namespace observe
}  // namespace nvib
