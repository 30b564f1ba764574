// State shared by every stepper: {t, u, v, a}, counters and the last failure.
// A stepper owns its workspace and its copy of the model; step() allocates nothing.
//
// Laws with memory: the model's internal variables are committed here, in advance(), the one
// place every scheme passes once per accepted step, at the accepted state. A failed step never
// reaches it, so it leaves every internal variable as it was.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "../base/types.hpp"
#include "../model/model.hpp"

namespace nvib {

// Brings the base's state into a derived stepper (a dependent base hides it).
#define NVIB_STEPPER_STATE(Base) \
  using Base::a_;                \
  using Base::stream_;           \
  using Base::h_;                \
  using Base::model_;            \
  using Base::n_;                \
  using Base::stats_;            \
  using Base::u_;                \
  using Base::v_

template <class ModelT>
class StepperBase {
 public:
  StepperBase(ModelT model, double h) : model_(std::move(model)), stream_(model_.can_stream()), h_(h) {
    check_time_step(h);
    const Index n = model_.size();
    u_.setZero(n);
    v_.setZero(n);
    a_.setZero(n);
  }

  double time() const { return t0_ + static_cast<double>(nt_) * h_; }
  std::int64_t step_index() const { return n_; }
  double dt() const { return h_; }
  Index size() const { return model_.size(); }
  const Vector& u() const { return u_; }
  const Vector& v() const { return v_; }
  const Vector& a() const { return a_; }
  const Stats& stats() const { return stats_; }
  Stats& stats() { return stats_; }
  const Failure& failure() const { return failure_; }
  ModelT& model() { return model_; }
  const ModelT& model() const { return model_; }
  // max |u_i| after the last step, where the step measured it as it updated u (NaN if some u_i is not
  // finite); negative where it did not: the loop's divergence test then reads u itself.
  double measured_max_u() const { return max_u_; }

  // Variable steps (adaptive runs, solve/adaptive.hpp). set_dt(h) makes the next steps h long from the
  // current time on; a stepper that carries a history at its step (a_{n-1}, PIM's remainders) hides it
  // with its own, which rescales that history first. checkpoint() keeps the state at an accepted step,
  // rollback() restores it exactly, step length included (the laws' committed internal variables too):
  // a step that is then retaken equals one taken without the detour. There are kCheckpoints slots: an
  // adaptive run keeps its companion's step start, its answer's state and step start, and the run's start.
  static constexpr int kCheckpoints = 4;
  void set_dt(double h) {
    if (h == h_) return;
    check_time_step(h);
    t0_ = time();
    nt_ = 0;
    h_ = h;
  }
  void checkpoint(int slot = 0) {
    Checkpoint& ck = ck_[checked_slot(slot)];
    ck.u = u_;
    ck.v = v_;
    ck.a = a_;
    ck.t0 = t0_;
    ck.h = h_;
    ck.n = n_;
    ck.nt = nt_;
    ck.laws.resize(model_.state_size());
    model_.get_state(ck.laws.data());
  }
  void rollback(int slot = 0) {
    const Checkpoint& ck = ck_[checked_slot(slot)];
    u_ = ck.u;
    v_ = ck.v;
    a_ = ck.a;
    t0_ = ck.t0;
    h_ = ck.h;
    n_ = ck.n;
    nt_ = ck.nt;
    model_.set_state(ck.laws.data());
    failure_ = Failure{};
    max_u_ = -1.0;
  }

  // The carried state as one vector: [u; v; a] (3n), followed by the history
  // a scheme keeps (its stepper documents it) and the committed internal
  // variables of the model's laws with memory. set_state(t, state()) leaves a
  // run unchanged; nvib.stability builds the amplification matrix of a linear
  // model from these, column by column, with the stepper itself.
  Index state_size() const { return 3 * size() + model_.state_size(); }
  Vector state() const {
    Vector x(state_size());
    pack_base(x);
    model_.get_state(x.data() + 3 * size());
    return x;
  }
  void set_state(double t, const Vector& x) {
    check_state(t, x, state_size());
    unpack_base(t, x);
    model_.set_state(x.data() + 3 * size());
  }

 protected:
  static size_t checked_slot(int slot) {
    NVIB_CHECK(slot >= 0 && slot < kCheckpoints, "slot", "must lie in [0, " + std::to_string(kCheckpoints) + "), got " +
                                                         std::to_string(slot));
    return static_cast<size_t>(slot);
  }
  void pack_base(Vector& x) const {
    const Index n = size();
    x.segment(0, n) = u_;
    x.segment(n, n) = v_;
    x.segment(2 * n, n) = a_;
  }
  void check_state(double t, const Vector& x, Index expected) const {
    NVIB_CHECK(std::isfinite(t), "t", "the time of the state must be finite");
    NVIB_CHECK(x.size() == expected, "state", "expected " + std::to_string(expected) + " entries, got " +
                                              std::to_string(x.size()));
    NVIB_CHECK(x.allFinite(), "state", "the state has non-finite entries");
  }
  // [u; v; a; h; internal variables] for a stepper that carries one more vector h (such as a_{n-1}).
  Index size_with(Index h) const { return 3 * size() + h + model_.state_size(); }
  Vector state_with(const Eigen::Ref<const Vector>& h) const {
    Vector x(size_with(h.size()));
    pack_base(x);
    x.segment(3 * size(), h.size()) = h;
    model_.get_state(x.data() + 3 * size() + h.size());
    return x;
  }
  template <class H>
  void set_state_with(double t, const Vector& x, H&& h) {
    check_state(t, x, size_with(h.size()));
    unpack_base(t, x);
    h = x.segment(3 * size(), h.size());
    model_.set_state(x.data() + 3 * size() + h.size());
  }
  // Sets t, u, v, a; the step counter restarts at t.
  void unpack_base(double t, const Vector& x) {
    const Index n = size();
    t0_ = t;
    n_ = 0;
    nt_ = 0;
    u_ = x.segment(0, n);
    v_ = x.segment(n, n);
    a_ = x.segment(2 * n, n);
    failure_ = Failure{};
    max_u_ = -1.0;
  }

  void check_initial(double t0, const Vector& u0, const Vector& v0) const {
    const Index n = model_.size();
    check_start_time(t0);
    NVIB_CHECK(u0.size() == n, "u0", "expected " + std::to_string(n) + " entries, got " + std::to_string(u0.size()));
    NVIB_CHECK(v0.size() == n, "v0", "expected " + std::to_string(n) + " entries, got " + std::to_string(v0.size()));
    NVIB_CHECK(u0.allFinite(), "u0", "the initial displacement has non-finite entries");
    NVIB_CHECK(v0.allFinite(), "v0", "the initial velocity has non-finite entries");
  }

  // Sets {t0, u0, v0} and a0 from the equation of motion (one force evaluation); the laws with
  // memory start from their initial states, committed at (u0, v0).
  void start(double t0, const Vector& u0, const Vector& v0) {
    check_initial(t0, u0, v0);
    t0_ = t0;
    n_ = 0;
    nt_ = 0;
    u_ = u0;
    v_ = v0;
    failure_ = Failure{};
    max_u_ = -1.0;
    model_.reset_state();
    model_.acceleration(u_, v_, t0_, a_, stats_);
    model_.commit(u_, v_, t0_, true);
    // Every scheme would carry inf or NaN from the first step on: refuse the start.
    for (Index i = 0; i < a_.size(); ++i)
      NVIB_CHECK(std::isfinite(a_[i]), "u0, v0", "the initial acceleration is not finite (a[" + std::to_string(i) +
                                                "] = " + detail::fmt(a_[i]) + "): the forces overflow at the initial state");
  }

  // Time the step under way is heading for (computed, never accumulated).
  double next_time() const { return t0_ + static_cast<double>(nt_ + 1) * h_; }

  // Bookkeeping at the end of a successful step, and the one commit of the laws with memory at the
  // accepted state {u, v} at the step's end. last_evaluation: the scheme's last force evaluation was
  // at that state (its trial is committed as it is); otherwise a new trial is made there.
  Status advance(bool last_evaluation = true) {
    ++n_;
    ++nt_;
    ++stats_.num_steps;
    model_.commit(u_, v_, time(), last_evaluation);
    return Status::success;
  }

  // An explicit scheme's step in one pass over memory where the model can (Model::stream_acceleration):
  // drift(p, q) updates u (and what the forces read of the velocity: forces_v) of DOFs p .. q-1, the
  // force goes to anew, which is divided by the lumped mass block by block, and kick(p, q) then uses
  // a_new of DOFs p .. q-1. max |u| is measured as u is updated (measured_max_u()), on DOFs still in cache.
  template <class Drift, class Kick>
  void streamed_step(const double* forces_v, double t1, double* anew, Drift&& drift, Kick&& kick) {
    const double* ndinv = model_.mass().negated_inverse().data();
    const bool uniform = model_.mass().is_uniform();
    double* u = u_.data();
    double umax = 0.0;
    bool finite = true;
    model_.stream_acceleration(
        u, forces_v, t1, anew, stats_,
        [&](Index p, Index q) {
          drift(p, q);
          detail::largest(q - p, u + p, umax, finite);
        },
        [&](Index p, Index q) {
          if (uniform)  // (one mass: one inverse, no array to read)
            scale(q - p, anew + p, ndinv[0]);
          else
            Mass::scale(q - p, anew + p, ndinv + p);
          kick(p, q);
        });
    max_u_ = finite ? umax : std::numeric_limits<double>::quiet_NaN();
  }
  static void scale(Index n, double* __restrict x, double w) {
    for (Index i = 0; i < n; ++i) x[i] *= w;
  }

  // A failed step: the stepper keeps its state before the step.
  Status fail(const Failure& f) {
    failure_ = f;
    return f.status;
  }

  ModelT model_;
  bool stream_ = false;  // the model can be stepped in one pass (Model::can_stream())
  double h_ = 0.0;
  double t0_ = 0.0;     // the time the current step length began at
  std::int64_t n_ = 0;  // steps since the start (or set_state)
  std::int64_t nt_ = 0; // steps since t0_: time() = t0_ + nt_ h_, computed, never accumulated
  struct Checkpoint {
    Vector u, v, a;
    std::vector<double> laws;
    double t0 = 0.0, h = 0.0;
    std::int64_t n = 0, nt = 0;
  };
  std::array<Checkpoint, kCheckpoints> ck_;
  Vector u_, v_, a_;
  double max_u_ = -1.0;  // measured_max_u()
  Stats stats_;
  Failure failure_;
};

// A stepper that also carries a_{n-1} (the two-level explicit schemes: CEMDTS, Zhai). The state is
// [u; v; a; a_{n-1}; internal variables of the laws with memory]; a_{-1} = a_0.
template <class ModelT>
class TwoLevelStepper : public StepperBase<ModelT> {
  using Base = StepperBase<ModelT>;

 public:
  TwoLevelStepper(ModelT model, double h) : Base(std::move(model), h) { aprev_.setZero(this->size()); }

  // Variable steps: a_{n-1} enters as the slope (a_n - a_{n-1}) / h; a new step h' keeps that slope by
  // carrying a_n - (h'/h) (a_n - a_{n-1}), the value a_{n-1} would have had a step of h' before.
  void set_dt(double h) {
    if (h == this->h_) return;
    const double r = h / this->h_;
    aprev_ = this->a_ - r * (this->a_ - aprev_);
    Base::set_dt(h);
  }
  void checkpoint(int slot = 0) {
    Base::checkpoint(slot);
    ck_aprev_[static_cast<size_t>(slot)] = aprev_;
  }
  void rollback(int slot = 0) {
    Base::rollback(slot);
    aprev_ = ck_aprev_[static_cast<size_t>(slot)];
  }

  // a_{n-1}, the acceleration of the step before the last (the error estimate's samples read it instead
  // of keeping a copy).
  const double* previous_a() const { return aprev_.data(); }

  Index state_size() const { return this->size_with(this->size()); }
  Vector state() const { return this->state_with(aprev_); }
  void set_state(double t, const Vector& x) { this->set_state_with(t, x, aprev_); }

 protected:
  // Base::start with a_{-1} = a_0.
  void start_two_level(double t0, const Vector& u0, const Vector& v0) {
    this->start(t0, u0, v0);
    aprev_ = this->a_;
  }

  Vector aprev_;
  std::array<Vector, Base::kCheckpoints> ck_aprev_;
};

}  // namespace nvib
