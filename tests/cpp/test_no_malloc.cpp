// step() must not allocate: Eigen's own allocations are trapped with
// EIGEN_RUNTIME_NO_MALLOC (its assertion made to throw), every other heap
// allocation (std::vector, std::string) by a counting global operator new.
#include <atomic>
#include <new>
#include <stdexcept>
#include <string>

#include "counting_new.hpp"  // first: it sets up Eigen's allocation check

#include <nvib/nvib.hpp>

#include "check.hpp"

struct Duffing {  // hardening spring + cubic damping, with an analytic tangent
  void operator()(const nvib::CVecRef& u, const nvib::CVecRef& v, double, nvib::VecRef out) const {
    for (nvib::Index i = 0; i < u.size(); ++i) out[i] = 100.0 * (1.0 + 30.0 * u[i] * u[i]) * u[i] + 0.1 * v[i] * v[i] * v[i];
  }
  void tangent(const nvib::CVecRef& u, const nvib::CVecRef& v, double, nvib::MatRef K, nvib::MatRef C) const {
    K.setZero();
    C.setZero();
    for (nvib::Index i = 0; i < u.size(); ++i) {
      K(i, i) = 100.0 * (1.0 + 90.0 * u[i] * u[i]);
      C(i, i) = 0.3 * v[i] * v[i];
    }
  }
};
struct NoTangent {  // forces the finite-difference tangent
  void operator()(const nvib::CVecRef& u, const nvib::CVecRef&, double t, nvib::VecRef out) const {
    for (nvib::Index i = 0; i < u.size(); ++i) out[i] = 50.0 * std::sin(u[i]) - std::cos(t);
  }
};

// u0: the initial displacement (default 0.3 on every DOF).
template <class Scheme, class ModelT>
void check_no_alloc(const char* what, const Scheme& scheme, const ModelT& model, const nvib::Vector* u0_ = nullptr) {
  const nvib::Index n = model.size();
  auto st = nvib::make_stepper(scheme, model, 1e-3);
  nvib::Vector u0 = u0_ ? *u0_ : nvib::Vector::Constant(n, 0.3), v0 = nvib::Vector::Zero(n);
  st.initialize(0.0, u0, v0);
  st.step();  // a first step outside the guard is allowed to warm nothing up, but must not be needed
  bool threw = false;
  g_news = 0;
  g_counting = true;
  Eigen::internal::set_is_malloc_allowed(false);
  try {
    for (int i = 0; i < 200; ++i) st.step();
  } catch (const std::exception& e) {
    threw = true;
    std::printf("%s: %s\n", what, e.what());
  }
  Eigen::internal::set_is_malloc_allowed(true);
  g_counting = false;
  if (threw || g_news != 0) std::printf("%s: allocated (eigen: %d, operator new: %ld)\n", what, threw, g_news.load());
  CHECK(!threw);
  CHECK(g_news == 0);
}

nvib::Newton mode(nvib::NewtonMode m) {
  nvib::Newton nw;
  nw.iteration = m;
  return nw;
}

// Every scheme of the registry with its defaults, then the variants that take other paths.
template <class ModelT>
void all_schemes(const std::string& label, const ModelT& model) {
  nvib::AllSchemes::for_each([&](auto* tag) {
    using S = std::remove_pointer_t<decltype(tag)>;
    check_no_alloc((label + " " + nvib::scheme_repr(S{})).c_str(), S{}, model);
  });
  check_no_alloc((label + " CentralDifference(half_step)").c_str(),
                 nvib::CentralDifference(nvib::CentralDifference::Velocity::half_step), model);
  for (auto m : {nvib::NewtonMode::modified, nvib::NewtonMode::initial, nvib::NewtonMode::incremental,
                 nvib::NewtonMode::one_iteration})
    check_no_alloc((label + " Newmark " + nvib::to_string(m)).c_str(), nvib::Newmark(0.25, 0.5, mode(m)), model);
  check_no_alloc((label + " GeneralizedAlpha rho 0.8").c_str(), nvib::GeneralizedAlpha::from_rho_inf(0.8), model);
  check_no_alloc((label + " PreciseIntegration order 3").c_str(), nvib::PreciseIntegration(20, 3, 2), model);
}

// Laws with memory on a sparse tangent: every scheme and variant, the implicit ones with the sparse
// the banded and the low-rank linear solvers forced (and checked to be the one used). Each step evaluates trials (the return
// mappings, Bouc-Wen's adaptive Runge-Kutta flow, the IMK branches) and commits one per accepted step
// (a swap of the trial and committed buffers, or a new trial at the end of a generalized-alpha step).
template <class ModelT>
void hysteretic_schemes(const std::string& label, const ModelT& model, const nvib::Vector& u0) {
  nvib::AllSchemes::for_each([&](auto* tag) {
    using S = std::remove_pointer_t<decltype(tag)>;
    if constexpr (S::is_explicit) check_no_alloc((label + " " + nvib::scheme_repr(S{})).c_str(), S{}, model, &u0);
  });
  check_no_alloc((label + " CentralDifference(half_step)").c_str(),
                 nvib::CentralDifference(nvib::CentralDifference::Velocity::half_step), model, &u0);
  for (auto choice : {nvib::LinearSolverChoice::sparse, nvib::LinearSolverChoice::banded, nvib::LinearSolverChoice::low_rank})
    for (auto m : {nvib::NewtonMode::newton, nvib::NewtonMode::modified, nvib::NewtonMode::initial,
                   nvib::NewtonMode::incremental, nvib::NewtonMode::one_iteration}) {
      nvib::Newton nw = mode(m);
      nw.linear_solver = choice;
      const nvib::Newmark nm(0.25, 0.5, nw);
      const std::string solver = nvib::to_string(choice);
      check_no_alloc((label + " Newmark " + solver + " " + nvib::to_string(m)).c_str(), nm, model, &u0);
      auto st = nvib::make_stepper(nm, model, 1e-3);
      st.initialize(0.0, u0, nvib::Vector::Zero(model.size()));
      st.step();
      const std::string used = st.stats().linear_solver;
      CHECK(choice == nvib::LinearSolverChoice::low_rank ? used.find("low-rank update") != std::string::npos
                                                          : used.find(solver) == 0);
    }
  nvib::Newton nw;
  nw.linear_solver = nvib::LinearSolverChoice::sparse;
  nvib::GeneralizedAlpha ga;  // alpha_f = 1/2: the end state gets a trial of its own at the commit
  ga.newton = nw;
  check_no_alloc((label + " GeneralizedAlpha sparse").c_str(), ga, model, &u0);
  nvib::GeneralizedAlpha rho = nvib::GeneralizedAlpha::from_rho_inf(0.8);
  rho.newton = nw;
  check_no_alloc((label + " GeneralizedAlpha rho 0.8 sparse").c_str(), rho, model, &u0);
}

int main() {
  // The guard itself must catch an allocation, or the test proves nothing.
  {
    bool caught = false;
    Eigen::internal::set_is_malloc_allowed(false);
    try {
      nvib::Vector tmp(64);
      tmp.setZero();
    } catch (const std::exception&) {
      caught = true;
    }
    Eigen::internal::set_is_malloc_allowed(true);
    CHECK(caught);
    g_news = 0;
    g_counting = true;
    auto* p = new std::string(100, 'x');
    g_counting = false;
    CHECK(g_news > 0);
    delete p;
  }
  const nvib::Index n = 12;  // above Eigen's small-size paths, so blocked LU kernels run too
  nvib::Matrix K = nvib::Matrix::Zero(n, n), C = nvib::Matrix::Zero(n, n);
  for (nvib::Index i = 0; i < n; ++i) {
    K(i, i) = 2e3;
    if (i > 0) K(i, i - 1) = K(i - 1, i) = -1e3;
    C(i, i) = 1.0;
  }
  nvib::Matrix Md = nvib::Matrix::Identity(n, n) * 2.0;
  for (nvib::Index i = 1; i < n; ++i) Md(i, i - 1) = Md(i - 1, i) = 0.5;

  all_schemes("diagonal mass, functor", nvib::make_model(nvib::Mass::diagonal(nvib::Vector::Ones(n)), Duffing{}, K, C));
  all_schemes("dense mass, functor", nvib::make_model(nvib::Mass::dense(Md), Duffing{}, K, C));
  all_schemes("finite-difference tangent", nvib::make_model(nvib::Mass::diagonal(nvib::Vector::Ones(n)), NoTangent{}, K));
  all_schemes("linear", nvib::make_linear_model(nvib::Mass::diagonal(nvib::Vector::Ones(n)), K, C));
  std::vector<nvib::effects::Effect> fx;
  for (nvib::Index i = 0; i < n; ++i) {
    fx.push_back(nvib::effects::hardening_spring({{i, 1.0}}, 100.0, 30.0));
    fx.push_back(nvib::effects::damper({{i, 1.0}}, 0.5));
    if (i > 0) fx.push_back(nvib::effects::cubic_spring({{i, 1.0}, {i - 1, -1.0}}, 10.0));
  }
  fx.push_back(nvib::effects::harmonic_force({{0, 1.0}}, 10.0, 3.0));
  all_schemes("effects", nvib::effects::make_effect_model(nvib::Mass::diagonal(nvib::Vector::Ones(n)), fx));
  // Every storage of a measure: a dense load written first, a sparse and a dense
  // measure, two arbitrary coefficients; then the same effects plus a functor.
  nvib::effects::Measure everywhere, dense, sparse;
  for (nvib::Index i = 0; i < n; ++i) everywhere.emplace_back(i, 1.0);
  for (nvib::Index i = 0; i < 8; ++i) dense.emplace_back(i, 0.1 * static_cast<double>(i + 1));
  sparse = {{0, 0.5}, {5, -0.3}, {9, 0.2}};
  fx.push_back(nvib::effects::ground_acceleration(everywhere, nvib::effects::Signal::sine(2.0, 1.5)));
  fx.push_back(nvib::effects::hardening_spring(sparse, 50.0, 3.0));
  fx.push_back(nvib::effects::cubic_spring(dense, 20.0));
  fx.push_back(nvib::effects::hertz_contact({{3, 0.7}, {4, -0.2}}, 1e-3, 2.0));
  fx.push_back(nvib::effects::constant_force({{2, 1.0}}, 3.0));
  all_schemes("effects, every storage", nvib::effects::make_effect_model(nvib::Mass::diagonal(nvib::Vector::Ones(n)), fx));
  all_schemes("effects plus a functor",
              nvib::effects::make_effect_model(nvib::Mass::diagonal(nvib::Vector::Ones(n)), fx, Duffing{}));
  // A sparse model: a consistent (tridiagonal) mass, sparse K, effect arrays; Newton's linear
  // solver is then sparse LDL^T (every tangent here is symmetric), whose refactorisations and
  // solves must reuse what set-up laid out. (Sparse LU, for nonsymmetric tangents, allocates in
  // Eigen's factorisation and is not held to this.)
  {
    const nvib::Index m = 100;
    std::vector<Eigen::Triplet<double, int>> tm, tk;
    for (int i = 0; i < m; ++i) {
      tm.emplace_back(i, i, 4.0);
      tk.emplace_back(i, i, 2e3);
      if (i > 0) {
        tm.emplace_back(i, i - 1, 1.0), tm.emplace_back(i - 1, i, 1.0);
        tk.emplace_back(i, i - 1, -1e3), tk.emplace_back(i - 1, i, -1e3);
      }
    }
    nvib::SparseMatrix Ms(m, m), Ks(m, m);
    Ms.setFromTriplets(tm.begin(), tm.end());
    Ks.setFromTriplets(tk.begin(), tk.end());
    std::vector<std::int32_t> i0, j0, i1;
    for (int i = 0; i < m; ++i) {
      i0.push_back(i), j0.push_back(i - 1), i1.push_back(i);  // j = -1: the first spring holds DOF 0 to the ground
    }
    std::vector<nvib::effects::EffectArray> arrays{
        nvib::effects::make_effect_array("hardening_spring", i0, j0, {{"k0", {100.0}}, {"a", {30.0}}}, m),
        nvib::effects::make_effect_array("power_damper", i1, {}, {{"c", {0.5}}, {"p", {1.5}}}, m),
        nvib::effects::make_effect_array("spring", i0, j0, {{"k", {10.0}}}, m)};
    std::vector<nvib::effects::Effect> loads{nvib::effects::harmonic_force({{0, 1.0}}, 10.0, 3.0)};
    all_schemes("sparse mass, sparse K", nvib::make_linear_model(nvib::Mass::sparse(Ms), Ks));
    all_schemes("effect arrays, diagonal mass",
                nvib::effects::make_effect_model(nvib::Mass::diagonal(nvib::Vector::Ones(m)), loads, arrays));
    all_schemes("effect arrays, sparse mass", nvib::effects::make_effect_model(nvib::Mass::sparse(Ms), loads, arrays));

    // Hysteresis: 100 bilinear storeys in an array (a chain from the ground), a Bouc-Wen element and an
    // IMK element on drifts of their own, and the ground shaking; started with alternating displacements
    // (drifts of 0.06, three times the storeys' yield drift) so that they yield from the first step on.
    std::vector<nvib::effects::EffectArray> storeys{
        nvib::effects::make_effect_array("bilinear", i0, j0, {{"k", {1e3}}, {"fy", {20.0}}, {"b", {0.05}}}, m),
        nvib::effects::make_effect_array("damper", i0, j0, {{"c", {0.5}}}, m)};
    std::vector<nvib::effects::Effect> singles{
        nvib::effects::make_effect("bouc_wen", {{50, 1.0}, {20, -1.0}}, {{"k", 500.0}, {"fy", 10.0}, {"alpha", 0.05}, {"n", 2.0}}),
        nvib::effects::make_effect("bouc_wen", {{70, 1.0}, {30, -1.0}},
                                   {{"k", 500.0}, {"fy", 10.0}, {"integration", 1.0}}),
        nvib::effects::make_effect("imk_peak_oriented", {{90, 1.0}, {40, -1.0}},
                                   {{"k", 500.0}, {"fy", 10.0}, {"up", 0.02}, {"upc", 0.2}, {"uu", 5.0}, {"fcap_fy", 1.2},
                                    {"fres_fy", 0.3}, {"lambda_s", 5.0}, {"lambda_k", 5.0}}),
        nvib::effects::make_effect("friction", {{10, 1.0}}, {{"k", 500.0}, {"fs", 5.0}}),
        nvib::effects::ground_acceleration([&] {
          nvib::effects::Measure r;
          for (nvib::Index i = 0; i < m; ++i) r.emplace_back(i, 1.0);
          return r;
        }(), nvib::effects::Signal::sine(20.0, 9.0))};
    {  // a chain long enough for the streamed explicit step (Model::stream_acceleration)
      const int big = 4 * static_cast<int>(nvib::Model<>::kStreamBlock) + 100;
      std::vector<std::int32_t> ib, jb;
      for (int i = 0; i < big; ++i) ib.push_back(i), jb.push_back(i - 1);
      std::vector<nvib::effects::EffectArray> chain{
          nvib::effects::make_effect_array("bilinear", ib, jb, {{"k", {1e3}}, {"fy", {20.0}}, {"b", {0.05}}}, big),
          nvib::effects::make_effect_array("damper", ib, jb, {{"c", {0.5}}}, big)};
      nvib::effects::Measure r;
      for (nvib::Index i = 0; i < big; ++i) r.emplace_back(i, 1.0);
      std::vector<nvib::effects::Effect> ground{nvib::effects::ground_acceleration(r, nvib::effects::Signal::sine(20.0, 9.0))};
      const auto streamed = nvib::effects::make_effect_model(nvib::Mass::diagonal(nvib::Vector::Ones(big)), ground, chain);
      CHECK(streamed.can_stream());
      nvib::Vector ub = nvib::Vector::Constant(big, 0.01);
      check_no_alloc("streamed chain, CentralDifference", nvib::CentralDifference(), streamed, &ub);
    }
    const auto hyst = nvib::effects::make_effect_model(nvib::Mass::diagonal(nvib::Vector::Ones(m)), singles, storeys);
    CHECK(hyst.has_state() && hyst.has_sparse_tangent() && !hyst.is_linear());
    CHECK(hyst.state_size() == 100 * 3 + 4 + 4 + 32 + 3);  // bilinear, bouc_wen x2, imk, friction
    nvib::Vector u0(m);
    for (nvib::Index i = 0; i < m; ++i) u0[i] = (i % 2 == 0 ? 0.03 : -0.03);
    hysteretic_schemes("hysteresis, sparse tangent", hyst, u0);
    // The storeys did yield while the guard was on: the committed plastic deformations moved.
    {
      auto st = nvib::make_stepper(nvib::Newmark(), hyst, 1e-3);
      st.initialize(0.0, u0, nvib::Vector::Zero(m));
      st.step();
      std::vector<double> first = st.model().nonlinear_force().state();
      for (int i = 0; i < 200; ++i) st.step();
      const std::vector<double>& later = st.model().nonlinear_force().state();
      int moved = 0;  // the storeys' plastic deformations: the last 200 entries (single effects come first)
      for (std::size_t k = later.size() - 200; k < later.size(); k += 2) moved += later[k] != first[k];
      CHECK(moved > 50);
    }
  }
  return nvib_test::finish("test_no_malloc");
}
