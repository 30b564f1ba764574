// The streamed explicit step (Model::stream_acceleration): a lumped-mass model whose effects reach a
// bounded distance along the DOFs is stepped block by block in one pass, with the same operations in
// the same order as the stage-by-stage step: the same bits (the central difference, CEMDTS, Zhai), on chains of every kind (arrays and single
// effects, uniform and per-effect parameters, laws with memory, loads of one value and of many, a linear
// K and C in a band, partial blocks), with and without the velocity predictor. The chain kernel
// (kernels::add_chain_forces) against a force summed effect by effect, and the divergence test the
// streamed step measures against the loop's own.
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include <nvib/nvib.hpp>

#include "check.hpp"

using nvib::Index;
using nvib::SparseMatrix;
using nvib::Vector;
namespace fx = nvib::effects;

namespace {

constexpr Index kN = 4 * nvib::Model<>::kStreamBlock + 777;  // the smallest streamed size, and a partial block

fx::EffectArray array_of(fx::LawId law, std::vector<std::int32_t> i, std::vector<std::int32_t> j,
                         std::vector<std::vector<double>> values) {
  fx::EffectArray a;
  a.law = law;
  a.i = std::move(i);
  a.j = std::move(j);
  a.values = std::move(values);
  return a;
}

// i = k + offset, j = i - 1 (the first to the ground where grounded).
void chain_indices(Index n, Index offset, bool grounded, std::vector<std::int32_t>& i, std::vector<std::int32_t>& j) {
  i.resize(static_cast<size_t>(n));
  j.resize(static_cast<size_t>(n));
  for (Index k = 0; k < n; ++k) {
    i[static_cast<size_t>(k)] = static_cast<std::int32_t>(k + offset);
    j[static_cast<size_t>(k)] = static_cast<std::int32_t>(k + offset - 1);
  }
  if (grounded) j[0] = -1;
}

template <class Scheme, class ModelT>
void same_bits_with(const Scheme& scheme, const std::string& what, ModelT model, bool velocity_free) {
  const Index n = model.size();
  Vector u0(n), v0(n);
  for (Index k = 0; k < n; ++k) {
    u0[k] = 1e-3 * std::sin(0.01 * double(k));
    v0[k] = velocity_free ? 0.0 : 1e-2 * std::cos(0.013 * double(k));
  }
  const double h = 2e-4;
  auto streamed = nvib::make_stepper(scheme, model, h);
  model.allow_stream(false);
  auto staged = nvib::make_stepper(scheme, model, h);
  CHECK(streamed.model().can_stream() && !staged.model().can_stream());
  streamed.initialize(0.0, u0, v0);
  staged.initialize(0.0, u0, v0);
  bool same = true;
  double moved = 0.0;
  for (int s = 0; s < 40; ++s) {
    const Vector before = streamed.a();
    CHECK(streamed.step() == nvib::Status::success && staged.step() == nvib::Status::success);
    // the acceleration of the step before, which the error estimate's samples read (previous_a())
    CHECK(streamed.previous_a() != nullptr && staged.previous_a() != nullptr);
    CHECK(Eigen::Map<const Vector>(streamed.previous_a(), n) == before);
    CHECK(Eigen::Map<const Vector>(staged.previous_a(), n) == before);
    same = same && streamed.u() == staged.u() && streamed.v() == staged.v() && streamed.a() == staged.a();
    // the step's measured max |u| is the one the loop would read
    CHECK(streamed.measured_max_u() == streamed.u().cwiseAbs().maxCoeff());
    CHECK(staged.measured_max_u() < 0.0);
  }
  moved = (streamed.u() - u0).cwiseAbs().maxCoeff();
  std::printf("%-72s same bits: %s (u moved by %.2e)\n", what.c_str(), same ? "yes" : "NO", moved);
  CHECK(same && moved > 0.0);
}

// Every explicit scheme that streams: the central difference, CEMDTS and Zhai's two-step method.
template <class ModelT>
void same_bits(const char* what, const ModelT& model, bool velocity_free = false) {
  same_bits_with(nvib::CentralDifference(), std::string("LCDM, ") + what, model, velocity_free);
  same_bits_with(nvib::CEMDTS(0.45), std::string("CEMDTS, ") + what, model, velocity_free);
  same_bits_with(nvib::Zhai(), std::string("Zhai, ") + what, model, velocity_free);
}

}  // namespace

int main() {
  const Index n = kN;
  std::vector<std::int32_t> i, j;
  // 1. The chain scene's pattern: hardening storeys and dampers along the DOFs, a ground motion, one mass.
  {
    chain_indices(n, 0, true, i, j);
    std::vector<fx::EffectArray> arrays{array_of(fx::law_id<fx::HardeningSpring>(), i, j, {{1e8}, {10.0}}),
                                        array_of(fx::law_id<fx::Damper>(), i, j, {{2e5}})};
    fx::Measure r;
    for (Index k = 0; k < n; ++k) r.emplace_back(k, 1.0);
    std::vector<fx::Effect> list{fx::ground_acceleration(r, fx::Signal::sine(10.0, 3.0))};
    same_bits("chain: hardening + dampers, uniform mass, ground motion",
              fx::make_effect_model(nvib::Mass::diagonal(Vector::Constant(n, 1e5)), std::move(list), std::move(arrays)));
  }
  // 2. Masses of many values, per-effect parameters, a law with memory, a partial ground motion (a row
  //    of many values), a constant load, a linear K and C in a band (K u + C v: the last stage).
  {
    chain_indices(n - 10, 5, false, i, j);  // offset, the first tied to DOF 4
    std::vector<double> k0(i.size()), fy(i.size());
    for (size_t k = 0; k < i.size(); ++k) {
      k0[k] = 1e4 * (1.0 + 0.3 * std::sin(double(k)));
      fy[k] = 2.0 + std::cos(0.1 * double(k));
    }
    std::vector<fx::EffectArray> arrays{array_of(fx::law_id<fx::Bilinear>(), i, j, {k0, fy, {0.05}}),
                                        array_of(fx::law_id<fx::CubicSpring>(), i, j, {{3e6}})};
    fx::Measure r;  // two DOFs in three (a dense row with zeros)
    for (Index k = 0; k < n; ++k)
      if (k % 3) r.emplace_back(k, 1.0);
    std::vector<fx::Effect> list{fx::ground_acceleration(r, fx::Signal::sine(2.0, 5.0)),
                                 fx::constant_force({{n / 2, 1.0}}, 3.0)};
    std::vector<Eigen::Triplet<double, int>> t;
    for (Index k = 0; k < n; ++k) {
      t.emplace_back(int(k), int(k), 200.0);
      if (k + 2 < n) t.emplace_back(int(k), int(k + 2), -50.0), t.emplace_back(int(k + 2), int(k), -50.0);
    }
    SparseMatrix K(n, n), C(n, n);
    K.setFromTriplets(t.begin(), t.end());
    Vector m(n);
    for (Index k = 0; k < n; ++k) m[k] = 1.0 + 0.5 * std::sin(0.3 * double(k));
    // K u + C v in each of its general forms (linear_product.hpp): C = beta K and C = alpha m + beta K
    // (rayleigh), C on K's pattern otherwise (shared), C on another pattern (rows)
    SparseMatrix Mm(n, n);
    for (Index k = 0; k < n; ++k) Mm.insert(k, k) = m[k];
    SparseMatrix other = 1e-3 * K;
    other.coeffRef(n / 2, n / 2) *= 1.5;  // not of Rayleigh's form
    SparseMatrix apart(n, n);             // dampers one DOF apart: another pattern than K's
    for (Index k = 0; k + 1 < n; ++k) apart.insert(k, k + 1) = -0.1, apart.insert(k + 1, k) = -0.1;
    for (Index k = 0; k < n; ++k) apart.insert(k, k) = 0.2;
    const std::pair<SparseMatrix, const char*> cs[] = {{SparseMatrix(1e-3 * K), "rayleigh"},
                                                      {SparseMatrix(SparseMatrix(0.3 * Mm) + SparseMatrix(1e-3 * K)), "rayleigh"},
                                                      {other, "shared"},
                                                      {apart, "rows"}};
    for (const auto& [C, form] : cs) {
      auto model = fx::make_effect_model(nvib::Mass::diagonal(m), list, arrays, K, C);
      CHECK(std::string(model.linear_product().form_name()) == form);
      same_bits((std::string("chain: bilinear + cubic, masses, partial ground motion, K + C ") + form).c_str(), model);
    }
  }
  // 3. Local but not a chain: ties two DOFs apart, in both orders, and ground springs (a general
  //    kernel in every stage); no velocity-dependent force (no predictor).
  {
    std::vector<std::int32_t> a(n - 2), b(n - 2), g(n);
    for (Index k = 0; k + 2 < n; ++k) a[k] = int(k + (k % 2 ? 2 : 0)), b[k] = int(k + (k % 2 ? 0 : 2));
    for (Index k = 0; k < n; ++k) g[k] = int(k);
    std::vector<fx::EffectArray> arrays{array_of(fx::law_id<fx::HardeningSpring>(), a, b, {{500.0}, {40.0}}),
                                        array_of(fx::law_id<fx::Spring>(), g, std::vector<std::int32_t>(n, -1), {{20.0}})};
    same_bits("ties two DOFs apart and ground springs, no predictor",
              fx::make_effect_model(nvib::Mass::diagonal(Vector::Constant(n, 2.0)), {}, std::move(arrays)), true);
  }
  // 4. Single effects (a shear building of many storeys, declared one by one: a group of pairs).
  {
    std::vector<fx::Effect> list;
    list.push_back(fx::hardening_spring({{0, 1.0}}, 1e4, 5.0));
    for (Index k = 1; k < n; ++k) list.push_back(fx::hardening_spring({{k, 1.0}, {k - 1, -1.0}}, 1e4, 5.0));
    for (Index k = 1; k < n; ++k) list.push_back(fx::damper({{k, 1.0}, {k - 1, -1.0}}, 0.5));
    same_bits("single effects: storeys and dampers", fx::make_effect_model(nvib::Mass::diagonal(Vector::Ones(n)), std::move(list)));
  }
  // 5. Not streamed: a dense measure (it reaches every DOF), a load on a sparse measure over the whole
  //    model (one effect reaching far from its index), a model too small.
  {
    chain_indices(n, 0, true, i, j);
    std::vector<fx::EffectArray> arrays{array_of(fx::law_id<fx::Spring>(), i, j, {{1.0}})};
    fx::Measure all;
    for (Index k = 0; k < n; ++k) all.emplace_back(k, 1.0 / double(n));
    std::vector<fx::Effect> list{fx::cubic_spring(all, 1.0)};
    auto dense_row = fx::make_effect_model(nvib::Mass::diagonal(Vector::Ones(n)), std::move(list), arrays);
    CHECK(!dense_row.can_stream());
    fx::Measure some;
    for (Index k = 0; k < n; k += 3) some.emplace_back(k, 1.0);
    std::vector<fx::Effect> loads{fx::ground_acceleration(some, fx::Signal::sine(2.0, 5.0))};
    auto sparse_load = fx::make_effect_model(nvib::Mass::diagonal(Vector::Ones(n)), std::move(loads), arrays);
    CHECK(!sparse_load.can_stream());
    auto small = fx::make_effect_model(nvib::Mass::diagonal(Vector::Ones(100)), {},
                                       std::vector<fx::EffectArray>{array_of(fx::law_id<fx::Spring>(), {0, 1}, {-1, 0}, {{1.0}})});
    CHECK(!small.can_stream());
  }
  // The chain kernel against the force summed effect by effect (f added at i, subtracted at j, in the
  // order of the effects), on a chain that starts away from DOF 0 and one tied to the ground.
  for (bool grounded : {false, true}) {
    const Index m = 700, offset = grounded ? 0 : 13;
    chain_indices(m, offset, grounded, i, j);
    std::vector<double> k0(i.size());
    for (size_t k = 0; k < i.size(); ++k) k0[k] = 100.0 + double(k % 7);
    std::vector<fx::EffectArray> arrays{array_of(fx::law_id<fx::HardeningSpring>(), i, j, {k0, {3.0}})};
    fx::EffectSet set({}, nvib::Mass::diagonal(Vector::Ones(m + offset)), nullptr, std::move(arrays));
    Vector u(m + offset), zero = Vector::Zero(m + offset), f(m + offset), ref = Vector::Zero(m + offset);
    for (Index k = 0; k < u.size(); ++k) u[k] = 0.1 * std::sin(0.7 * double(k));
    set.eval(u.data(), zero.data(), 0.0, f.data());
    for (size_t k = 0; k < i.size(); ++k) {
      const double d = u[i[k]] - (j[k] >= 0 ? u[j[k]] : 0.0), force = k0[k] * (1.0 + 3.0 * d * d) * d;
      ref[i[k]] += force;
      if (j[k] >= 0) ref[j[k]] -= force;
    }
    CHECK(f == ref);
  }
  // The loop's divergence test (displacement_ok) against its definition, entry by entry: every |u_i| <=
  // bound and finite; on sizes unrolled, looped and across its blocks, with the offending entry first,
  // in the middle and last.
  {
    int cases = 0;
    const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
    for (Index m : {1, 2, 5, 8, 9, 100, 1023, 1024, 1025, 3001}) {
      Vector u(m);
      for (Index k = 0; k < m; ++k) u[k] = 0.5 * std::sin(1.3 * double(k));
      for (double bound : {inf, 2.0, 0.5}) {
        auto reference = [&](const Vector& x) {
          for (Index k = 0; k < x.size(); ++k)
            if (!std::isfinite(x[k]) || !(std::abs(x[k]) <= std::min(bound, std::numeric_limits<double>::max())))
              return false;
          return true;
        };
        CHECK(nvib::displacement_ok(u, bound) == reference(u));
        for (Index at : {Index(0), m / 2, m - 1})
          for (double bad : {nan, inf, -inf, -3.0, 0.5000000000000001, std::numeric_limits<double>::max()}) {
            Vector w = u;
            w[at] = bad;
            CHECK(nvib::displacement_ok(w, bound) == reference(w));
            ++cases;
          }
      }
    }
    std::printf("displacement_ok: %d cases as its definition\n", cases);
  }
  // The half-step velocity keeps no a_{n-1} (its step updates a in place): previous_a() says so, and
  // the error estimate keeps its own copy.
  {
    auto model = fx::make_effect_model(nvib::Mass::diagonal(Vector::Ones(3)), {fx::hardening_spring({{0, 1.0}}, 4.0, 1.0)});
    auto st = nvib::make_stepper(nvib::CentralDifference(nvib::CentralDifference::Velocity::half_step), model, 0.01);
    st.initialize(0.0, Vector::Constant(3, 0.1), Vector::Zero(3));
    CHECK(st.step() == nvib::Status::success && st.previous_a() == nullptr);
  }
  return nvib_test::finish("test_stream");
}
