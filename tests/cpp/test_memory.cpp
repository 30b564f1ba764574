// Laws with memory at the C++ level:
//  - 10^6 bilinear springs in one effect array build in seconds (the time is printed, not asserted)
//    and a step of an explicit and of an implicit (sparse) scheme allocates nothing;
//  - what Newmark and generalized-alpha (alpha_f != 0) commit is a new trial at the accepted state from
//    the state committed before the step, bit for bit; EffectSet::verify_commits checks it on every
//    commit of a last trial and does catch a trial made elsewhere;
//  - a failed Newton step leaves the EffectSet's committed state (and u, v, a) as it was.
#include <atomic>
#include <chrono>
#include <cstdio>
#include <new>
#include <stdexcept>
#include <string>
#include <vector>

#include "counting_new.hpp"  // first: it sets up Eigen's allocation check

#include <nvib/nvib.hpp>

#include "check.hpp"

using nvib::Index;
using nvib::Vector;
namespace fx = nvib::effects;

namespace {

// Runs `steps` steps with every allocation trapped; true if none happened (and every step succeeded).
template <class Stepper>
bool steps_allocate_nothing(Stepper& st, int steps, const char* what) {
  bool threw = false, ok = true;
  g_news = 0;
  g_counting = true;
  Eigen::internal::set_is_malloc_allowed(false);
  try {
    for (int i = 0; i < steps; ++i) ok = ok && st.step() == nvib::Status::success;
  } catch (const std::exception& e) {
    threw = true;
    std::printf("%s: %s\n", what, e.what());
  }
  Eigen::internal::set_is_malloc_allowed(true);
  g_counting = false;
  if (threw || g_news != 0 || !ok)
    std::printf("%s: allocated (eigen: %d, operator new: %ld), steps ok: %d\n", what, threw, g_news.load(), ok);
  return !threw && g_news == 0 && ok;
}

// A chain of n DOFs (unit masses) held by n bilinear storeys d_k = u_k - u_{k-1} (the first to the ground).
fx::EffectArray storeys(Index n, double k, double fy, double b) {
  std::vector<std::int32_t> i(static_cast<size_t>(n)), j(static_cast<size_t>(n));
  for (Index q = 0; q < n; ++q) {
    i[static_cast<size_t>(q)] = static_cast<std::int32_t>(q);
    j[static_cast<size_t>(q)] = static_cast<std::int32_t>(q - 1);
  }
  return fx::make_effect_array("bilinear", std::move(i), std::move(j), {{"k", {k}}, {"fy", {fy}}, {"b", {b}}}, n, {},
                               "storeys");
}

Vector alternating(Index n, double a) {
  Vector u(n);
  for (Index q = 0; q < n; ++q) u[q] = q % 2 == 0 ? a : -a;
  return u;
}

void a_million_springs() {
  const Index n = 1000000;
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<fx::EffectArray> arrays{storeys(n, 1e3, 10.0, 0.05)};
  const auto model = fx::make_effect_model(nvib::Mass::diagonal(Vector::Ones(n)), {}, std::move(arrays));
  const double built = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("test_memory: 10^6 bilinear springs in an array built in %.3f s\n", built);
  CHECK(model.state_size() == 3 * n && model.has_state() && model.has_sparse_tangent());
  // drifts of 0.04 = 4 yield drifts: every storey yields at the first steps
  const Vector u0 = alternating(n, 0.02), v0 = Vector::Zero(n);
  {
    auto st = nvib::make_stepper(nvib::CentralDifference(), model, 1e-3);
    st.initialize(0.0, u0, v0);
    st.step();
    CHECK(steps_allocate_nothing(st, 5, "10^6 springs, CentralDifference"));
    const std::vector<double>& s = st.model().nonlinear_force().state();
    CHECK(s[0] != 0.0 && s[2 * 999999] != 0.0);  // plastic deformations of the first and last storeys
  }
  {
    nvib::Newton nw;
    nw.linear_solver = nvib::LinearSolverChoice::sparse;
    auto st = nvib::make_stepper(nvib::Newmark(0.25, 0.5, nw), model, 1e-3);
    const auto t1 = std::chrono::steady_clock::now();
    st.initialize(0.0, u0, v0);
    st.step();
    std::printf("test_memory: Newmark's first step (the sparse analysis) on 10^6 springs took %.3f s\n",
                std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count());
    CHECK(steps_allocate_nothing(st, 2, "10^6 springs, Newmark (sparse LDLT)"));
    CHECK(std::string(st.stats().linear_solver).find("sparse") == 0);
  }
}

// Every law with memory on a small chain, shaken hard: bilinear storeys (an array), Bouc-Wen of both
// integrations, friction and IMK. The committed states are laid out single effects first (grouped by
// law), then the arrays: the six storeys' (plastic deformation, dissipated) are the last 12 entries.
nvib::Model<fx::EffectSet> hysteretic_chain() {
  const Index n = 6;
  std::vector<fx::EffectArray> arrays{storeys(n, 400.0, 4.0, 0.05)};
  fx::Measure all;
  for (Index q = 0; q < n; ++q) all.emplace_back(q, 1.0);
  std::vector<fx::Effect> singles{
      fx::make_effect("bouc_wen", {{3, 1.0}, {1, -1.0}}, {{"k", 300.0}, {"fy", 3.0}, {"alpha", 0.1}, {"n", 2.0}}),
      fx::make_effect("bouc_wen", {{5, 1.0}, {2, -1.0}}, {{"k", 200.0}, {"dy", 0.02}, {"integration", 1.0}}),
      fx::make_effect("friction", {{4, 1.0}, {3, -1.0}}, {{"k", 300.0}, {"mu", 0.25}, {"N", 12.0}}),
      fx::make_effect("imk_peak_oriented", {{5, 1.0}},
                      {{"k", 300.0}, {"fy", 3.0}, {"up", 0.02}, {"upc", 0.3}, {"uu", 2.0}, {"fcap_fy", 1.2},
                       {"fres_fy", 0.3}, {"lambda_s", 20.0}, {"lambda_k", 30.0}}),
      fx::damper({{0, 1.0}}, 0.5),
      fx::ground_acceleration(all, fx::Signal::sine(8.0, 7.0))};
  return fx::make_effect_model(nvib::Mass::diagonal(Vector::Ones(n)), std::move(singles), std::move(arrays));
}

// After every step of `scheme`, the committed state equals a new trial at the accepted (u, v, t) made
// from the state committed before the step, bit for bit; returns the number of steps in which some
// bilinear storey yielded.
template <class Scheme>
int commits_are_trials_at_the_accepted_state(const Scheme& scheme, const char* what) {
  auto model = hysteretic_chain();
  model.nonlinear_force().verify_commits(true);  // the stepper's copy checks every commit of a last trial
  auto st = nvib::make_stepper(scheme, model, 2e-3);
  st.initialize(0.0, Vector::Zero(model.size()), Vector::Zero(model.size()));
  int changed = 0, mismatches = 0;
  try {
    for (int i = 0; i < 1500; ++i) {
      const std::vector<double> before = st.model().nonlinear_force().state();
      if (st.step() != nvib::Status::success) {
        std::printf("%s: step %d failed: %s\n", what, i + 1, st.failure().message.c_str());
        ++mismatches;
        break;
      }
      fx::EffectSet fresh = st.model().nonlinear_force();  // a copy: the compiled effects and its own states
      fresh.verify_commits(false);
      fresh.set_state(before.data());
      fresh.commit_at(st.u().data(), st.v().data(), st.time());
      const std::vector<double>& committed = st.model().nonlinear_force().state();
      mismatches += fresh.state() != committed;
      bool slipped = false;  // a bilinear storey's plastic deformation moved
      for (std::size_t q = committed.size() - 18; q < committed.size(); q += 3) slipped = slipped || committed[q] != before[q];
      changed += slipped;
    }
  } catch (const std::logic_error& e) {  // verify_commits: a last trial that was not at the accepted state
    std::printf("%s: %s\n", what, e.what());
    ++mismatches;
  }
  CHECK(mismatches == 0);
  std::printf("test_memory: %s: 1500 commits, each a trial at the accepted state; storeys yielded in %d steps\n", what,
              changed);
  return changed;
}

void commits() {
  // Newmark (and generalized-alpha with alpha_f = 0): Newton's last evaluation is at the accepted state,
  // its trial is committed as it is, checked by verify_commits and against a new trial here.
  CHECK(commits_are_trials_at_the_accepted_state(nvib::Newmark(), "Newmark") > 100);
  nvib::Newton one;
  one.iteration = nvib::NewtonMode::one_iteration;
  CHECK(commits_are_trials_at_the_accepted_state(nvib::Newmark(0.25, 0.5, one), "Newmark one_iteration") > 100);
  // Generalized-alpha with alpha_f != 0: Newton's last evaluation is at the alpha-point; the commit is a
  // new trial at the end of the step.
  CHECK(commits_are_trials_at_the_accepted_state(nvib::GeneralizedAlpha(), "GeneralizedAlpha (alpha_f = 1/2)") > 100);
  CHECK(commits_are_trials_at_the_accepted_state(nvib::GeneralizedAlpha::hht(-0.1), "HHT (alpha_f = 0.1)") > 100);
  CHECK(commits_are_trials_at_the_accepted_state(nvib::GeneralizedAlpha::from_rho_inf(0.8), "GeneralizedAlpha rho 0.8") > 100);
  CHECK(commits_are_trials_at_the_accepted_state(nvib::CentralDifference(), "CentralDifference") > 100);
  CHECK(commits_are_trials_at_the_accepted_state(nvib::PreciseIntegration(), "PreciseIntegration") > 100);

  // The alpha-point trial is not the end state's: committing it would be wrong, and verify_commits says so.
  {
    auto model = hysteretic_chain();
    fx::EffectSet& set = model.nonlinear_force();
    set.verify_commits(true);
    const Index n = model.size();
    const Vector u1 = alternating(n, 0.05), u2 = 0.5 * u1, v = Vector::Zero(n);
    Vector f(n);
    set(u1, v, 0.0, f);  // a trial at u1 (every storey yields there) ...
    bool caught = false;
    try {
      set.commit_last_trial(u2.data(), v.data(), 0.0);  // ... committed as if it were at u2
    } catch (const std::logic_error& e) {
      caught = std::string(e.what()).find("commit: the last trial's state differs") == 0;
    }
    CHECK(caught);
    // committed where it was made, it passes
    set(u1, v, 0.0, f);
    bool threw = false;
    try {
      set.commit_last_trial(u1.data(), v.data(), 0.0);
    } catch (const std::logic_error&) {
      threw = true;
    }
    CHECK(!threw);
    CHECK(set.state()[set.state().size() - 18] != 0.0);  // the first storey's plastic deformation
  }
}

// A stepper with too few Newton iterations, given the state a converged run reached after 0.6 s of
// yielding, steps until a step fails; the committed state, u, v and a are then those before it.
template <class Scheme>
void failed_step_changes_nothing(const Scheme& good, const Scheme& scheme, const char* what) {
  const auto model = hysteretic_chain();
  auto ref = nvib::make_stepper(good, model, 2e-3);
  ref.initialize(0.0, Vector::Zero(6), Vector::Zero(6));
  for (int i = 0; i < 300; ++i) ref.step();
  auto st = nvib::make_stepper(scheme, model, 2e-3);
  st.initialize(0.0, Vector::Zero(6), Vector::Zero(6));
  st.set_state(ref.time(), ref.state());
  for (int i = 0; i < 3000; ++i) {
    const std::vector<double> state = st.model().nonlinear_force().state();
    const Vector u = st.u(), v = st.v(), a = st.a();
    const std::int64_t k = st.step_index();
    if (st.step() != nvib::Status::success) {
      CHECK(st.failure().status == nvib::Status::newton_failed);
      CHECK(st.model().nonlinear_force().state() == state);
      CHECK(st.u() == u && st.v() == v && st.a() == a && st.step_index() == k);
      bool yielded = false;
      for (std::size_t q = state.size() - 18; q < state.size(); q += 3) yielded = yielded || state[q] != 0.0;
      CHECK(yielded);
      // the same step again: the same failure, still nothing changed
      CHECK(st.step() == nvib::Status::newton_failed);
      CHECK(st.model().nonlinear_force().state() == state && st.u() == u);
      std::printf("test_memory: %s failed %lld steps after the restart, as intended\n", what,
                  static_cast<long long>(k + 1));
      return;
    }
  }
  std::printf("%s: no step failed\n", what);
  CHECK(false);
}

void failed_steps() {
  nvib::Newton nw;
  nw.max_iter = 1;
  failed_step_changes_nothing(nvib::Newmark(), nvib::Newmark(0.25, 0.5, nw), "Newmark, 1 iteration");
  nvib::GeneralizedAlpha ga;
  ga.newton = nw;
  failed_step_changes_nothing(nvib::GeneralizedAlpha(), ga, "GeneralizedAlpha, 1 iteration");
  nvib::Newton modified;
  modified.iteration = nvib::NewtonMode::modified;
  nvib::Newton modified2 = modified;
  modified2.max_iter = 2;
  failed_step_changes_nothing(nvib::Newmark(0.25, 0.5, modified), nvib::Newmark(0.25, 0.5, modified2),
                              "Newmark modified, 2 iterations");
}

}  // namespace

// Adaptive steps: a step retaken after a rejection equals the step taken once. reject_every = 3 tries
// every third step first at twice its length (rescaling the scheme's history, refactorising, committing
// the laws' trial states) and rejects it whatever its error; the accepted steps must be the same bit
// for bit, on the chain of every law with memory, its bilinear storeys landing on their yield points.
template <class Scheme>
void rejections_leave_no_trace(const Scheme& scheme, const char* what) {
  const auto model = hysteretic_chain();
  const Index n = model.size();
  nvib::SolveOptions opt;
  opt.tol = 1e-3;
  const auto once = nvib::solve(model, scheme, 2e-3, 1.0, Vector::Zero(n), Vector::Zero(n), opt);
  opt.reject_every = 3;
  const auto detours = nvib::solve(model, scheme, 2e-3, 1.0, Vector::Zero(n), Vector::Zero(n), opt);
  CHECK(once.status == nvib::Status::success && detours.status == nvib::Status::success);
  CHECK(once.t.size() == detours.t.size() && once.t.size() > 100);
  const bool same = once.t == detours.t && once.u == detours.u && once.v == detours.v && once.a == detours.a &&
                    once.error_estimate == detours.error_estimate;
  CHECK(same);
  // The detours are the companion's (the run on double steps that measures the error): every third of its steps.
  CHECK(detours.stats.num_rejected_steps >= once.stats.num_rejected_steps + once.stats.num_check_steps / 3);
  CHECK(once.stats.num_events >= 3);  // the storeys' yield points (5 in every scheme's run)
  std::printf("test_memory: %s adaptive (tol 1e-3): %lld steps (%lld restarts), %lld events; with a rejected detour "
              "every third step the same bit for bit: %s\n", what, static_cast<long long>(once.stats.num_steps),
              static_cast<long long>(once.stats.num_restarts), static_cast<long long>(once.stats.num_events),
              same ? "yes" : "NO");
}

void rejections() {
  rejections_leave_no_trace(nvib::CentralDifference(), "CentralDifference");
  rejections_leave_no_trace(nvib::CentralDifference(nvib::CentralDifference::Velocity::half_step), "CentralDifference half-step");
  rejections_leave_no_trace(nvib::CEMDTS(), "CEMDTS");
  rejections_leave_no_trace(nvib::Zhai(), "Zhai");
  rejections_leave_no_trace(nvib::Newmark(), "Newmark");
  rejections_leave_no_trace(nvib::GeneralizedAlpha(), "GeneralizedAlpha");
}

int main() {
  std::setvbuf(stdout, nullptr, _IONBF, 0);
  // The guard must catch an allocation, or the test proves nothing.
  {
    g_news = 0;
    g_counting = true;
    auto* p = new std::vector<double>(100);
    g_counting = false;
    CHECK(g_news > 0);
    delete p;
  }
  commits();
  failed_steps();
  rejections();
  a_million_springs();
  return nvib_test::finish("test_memory");
}
