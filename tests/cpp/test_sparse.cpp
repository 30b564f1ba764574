// Sparse models: the sparse linear solvers (LDL^T for symmetric iteration
// matrices, LU otherwise) give the dense LU's trajectories to round-off, a
// sparse consistent mass gives its dense equivalent's, and the automatic
// choice picks what it says. K u + C v (LinearProduct) takes its band form
// exactly where K and C are complete bands of half-width <= 2, and gives the
// compressed rows' sums bit for bit either way; its rayleigh form (C = alpha m +
// beta K with a lumped mass) and shared form (C on K's pattern) are taken for
// the C they are meant for and give those sums to round-off.
#include <nvib/nvib.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "check.hpp"

using nvib::Index;
using nvib::Matrix;
using nvib::SparseMatrix;
using nvib::Vector;
namespace fx = nvib::effects;

namespace {

// A chain of n DOFs: a hardening spring and a damper to the ground on DOF 0, hardening springs
// and dampers between neighbours, a ground acceleration on every DOF.
std::vector<fx::Effect> chain(Index n) {
  std::vector<fx::Effect> list;
  list.push_back(fx::hardening_spring({{0, 1.0}}, 1e4, 50.0));
  list.push_back(fx::damper({{0, 1.0}}, 2.0));
  for (Index i = 1; i < n; ++i) {
    list.push_back(fx::hardening_spring({{i, 1.0}, {i - 1, -1.0}}, 1e4 * (1.0 + 0.01 * double(i)), 50.0));
    list.push_back(fx::damper({{i, 1.0}, {i - 1, -1.0}}, 2.0));
  }
  fx::Measure r;
  for (Index i = 0; i < n; ++i) r.emplace_back(i, 1.0);
  list.push_back(fx::ground_acceleration(r, fx::Signal::sine(5.0, 20.0)));
  return list;
}

nvib::Newton with_solver(nvib::NewtonMode mode, nvib::LinearSolverChoice c) {
  nvib::Newton nw;
  nw.iteration = mode;
  nw.linear_solver = c;
  return nw;
}

double rel_diff(const nvib::History& a, const nvib::History& b) {
  return (a - b).cwiseAbs().maxCoeff() / std::max(b.cwiseAbs().maxCoeff(), 1e-300);
}

template <class Scheme, class ModelT>
void same_with_both_solvers(const char* what, const ModelT& model, Scheme dense, Scheme sparse, const char* expected,
                            double tol = 1e-12) {
  const Index n = model.size();
  const Vector u0 = Vector::Constant(n, 1e-3), v0 = Vector::LinSpaced(n, -0.1, 0.1);
  const auto a = nvib::solve(model, dense, 1e-3, 0.2, u0, v0);
  const auto b = nvib::solve(model, sparse, 1e-3, 0.2, u0, v0);
  CHECK(a.status == nvib::Status::success && b.status == nvib::Status::success);
  CHECK(std::string(a.stats.linear_solver) == "dense LU");
  CHECK(std::string(b.stats.linear_solver) == expected);
  const double du = rel_diff(b.u, a.u), dv = rel_diff(b.v, a.v), da = rel_diff(b.a, a.a);
  std::printf("%-45s %-11s u %.1e v %.1e a %.1e, Newton it. %lld / %lld\n", what, expected, du, dv, da,
              static_cast<long long>(a.stats.num_newton_iters), static_cast<long long>(b.stats.num_newton_iters));
  CHECK(du <= tol && dv <= tol && da <= 100 * tol);
}

// A random matrix with the entries (i, j), |i - j| <= B (B < 0: none), minus those `holes` names.
SparseMatrix band_matrix(Index n, int B, std::mt19937& gen, const std::vector<std::pair<Index, Index>>& holes = {}) {
  std::uniform_real_distribution<double> value(-2.0, 2.0);
  std::vector<Eigen::Triplet<double, int>> t;
  for (Index i = 0; i < n; ++i)
    for (Index j = std::max<Index>(0, i - B); j <= std::min<Index>(n - 1, i + B); ++j)
      if (std::find(holes.begin(), holes.end(), std::make_pair(i, j)) == holes.end())
        t.emplace_back(static_cast<int>(i), static_cast<int>(j), value(gen));
  SparseMatrix A(n, n);
  A.setFromTriplets(t.begin(), t.end());
  A.makeCompressed();
  return A;
}

// out0 + K u + C v row by row, K's stored entries then C's, columns ascending: the order both ways of
// LinearProduct promise.
Vector rows_reference(const SparseMatrix& K, const SparseMatrix& C, const Vector& u, const Vector& v,
                      const Vector& out0) {
  const Eigen::SparseMatrix<double, Eigen::RowMajor, int> Kr = K, Cr = C;
  Vector out = out0;
  for (Index i = 0; i < out.size(); ++i) {
    double s = out[i];
    for (decltype(Kr)::InnerIterator it(Kr, i); it; ++it) s += it.value() * u[it.col()];
    for (decltype(Cr)::InnerIterator it(Cr, i); it; ++it) s += it.value() * v[it.col()];
    out[i] = s;
  }
  return out;
}

bool bitwise_equal(const Vector& a, const Vector& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<std::size_t>(a.size())) == 0;
}

void linear_product_cases() {
  std::mt19937 gen(2718);
  std::normal_distribution<double> normal(0.0, 1.0);
  int banded = 0, general = 0;
  for (Index n : {1, 2, 3, 4, 5, 6, 7, 9, 40}) {
    Vector u(n), v(n), out0(n);
    for (Index i = 0; i < n; ++i) u[i] = normal(gen), v[i] = normal(gen), out0[i] = normal(gen);
    auto check = [&](const SparseMatrix& K, const SparseMatrix& C, bool expect_band) {
      const nvib::LinearProduct p(K, C);
      CHECK(p.banded() == expect_band);
      Vector out = out0;
      p.add(u.data(), v.data(), out.data());
      CHECK(bitwise_equal(out, rows_reference(K, C, u, v, out0)));
      (expect_band ? banded : general) += 1;
    };
    for (int bk = -1; bk <= 2; ++bk)
      for (int bc = -1; bc <= 2; ++bc) {
        if (bk < 0 && bc < 0) continue;
        const SparseMatrix K = bk < 0 ? SparseMatrix(n, n) : band_matrix(n, bk, gen);
        const SparseMatrix C = bc < 0 ? SparseMatrix(n, n) : band_matrix(n, bc, gen);
        check(K, C, true);
      }
    if (n >= 2) {  // an entry missing from the band: the compressed rows
      check(band_matrix(n, 1, gen, {{0, 1}}), band_matrix(n, 1, gen), false);
      check(band_matrix(n, 1, gen), band_matrix(n, 2, gen, {{n - 1, n - 2}}), false);
    }
    if (n >= 4) check(band_matrix(n, 3, gen), SparseMatrix(n, n), false);  // wider than 2
  }
  std::printf("LinearProduct: %d band cases and %d general ones, bit for bit with the rows\n", banded, general);
  // Bands whose diagonals hold one value over a run of rows (uniform storeys): those rows multiply by
  // constants, the same products in the same order. The run is the longest around the middle row, of
  // interior rows only; a row that differs (another storey, or a value of another sign of zero) ends it.
  int runs = 0;
  for (Index n : {60, 70, 200, 1001}) {
    Vector u(n), v(n), out0(n);
    for (Index i = 0; i < n; ++i) u[i] = normal(gen), v[i] = normal(gen), out0[i] = normal(gen);
    // A band of half-width B with diagonal o's value d[o + B] in every row, row `odd` (if >= 0)
    // changed to `odd_value` on its diagonal, and the last row's diagonal another (a chain's top).
    auto uniform_band = [&](int B, std::vector<double> d, Index odd, double odd_value) {
      std::vector<Eigen::Triplet<double, int>> t;
      for (Index i = 0; i < n; ++i)
        for (Index j = std::max<Index>(0, i - B); j <= std::min<Index>(n - 1, i + B); ++j) {
          double x = d[static_cast<size_t>(j - i + B)];
          if (i == j && i == odd) x = odd_value;
          if (i == j && i == n - 1) x += 1.0;
          t.emplace_back(static_cast<int>(i), static_cast<int>(j), x);
        }
      SparseMatrix A(n, n);
      A.setFromTriplets(t.begin(), t.end());
      return A;
    };
    for (int bk = -1; bk <= 2; ++bk)
      for (int bc = -1; bc <= 2; ++bc) {
        if (bk < 0 && bc < 0) continue;
        const int B = std::max({bk, bc, 0});
        for (Index odd : {Index(-1), n / 2 + 3, n / 3}) {
          for (double odd_value : {7.5, -0.0}) {
            std::vector<double> dk(static_cast<size_t>(2 * std::max(bk, 0) + 1)), dc(static_cast<size_t>(2 * std::max(bc, 0) + 1));
            for (double& x : dk) x = normal(gen);
            for (double& x : dc) x = normal(gen);
            if (bc >= 0) dc[static_cast<size_t>(bc)] = 0.0;  // a diagonal of +0.0: -0.0 differs from it
            const SparseMatrix K = bk < 0 ? SparseMatrix(n, n) : uniform_band(bk, dk, -1, 0.0);
            const SparseMatrix C = bc < 0 ? SparseMatrix(n, n) : uniform_band(bc, dc, odd, odd_value);
            const nvib::LinearProduct p(K, C);
            CHECK(p.banded());
            // The expected run: interior rows B .. n - B - 1 less the top row (its other diagonal) and,
            // where C's changed row lies at or above the middle row, the rows from it on.
            const Index lo = B, hi = n - B, mid = lo + (hi - lo) / 2;
            Index a = lo, z = std::min(hi, n - 1);
            if (bc >= 0 && odd >= 0) {
              if (odd > mid)
                z = std::min(z, odd);
              else
                a = std::max(a, odd + 1);
            }
            const bool run = z - a >= nvib::LinearProduct::kConstantRows;
            CHECK(p.constant_rows() == (run ? std::make_pair(a, z) : std::make_pair(Index(0), Index(0))));
            runs += run;
            const Vector ref = rows_reference(K, C, u, v, out0);
            Vector out = out0;
            p.add(u.data(), v.data(), out.data());
            CHECK(bitwise_equal(out, ref));
            // in pieces, as the streamed step asks for rows (pieces across the run's ends)
            out = out0;
            for (Index r0 = 0; r0 < n; r0 += 37) p.add(u.data(), v.data(), out.data(), r0, std::min(n, r0 + 37));
            CHECK(bitwise_equal(out, ref));
          }
        }
      }
  }
  std::printf("LinearProduct: %d bands with a run of constant rows, bit for bit with the rows\n", runs);
  CHECK(runs > 0);
}

// A symmetric FE-like pattern: K_ii = 4 + |row|, K_ij = -1 for a few random j within +-12 of i (a
// mesh's numbering), both triangles.
SparseMatrix scattered_symmetric(Index n, std::mt19937& gen) {
  std::uniform_int_distribution<int> offset(1, 12);
  std::uniform_real_distribution<double> value(0.5, 1.5);
  std::vector<Eigen::Triplet<double, int>> t;
  for (Index i = 0; i < n; ++i) {
    double row = 0.0;
    for (int e = 0; e < 3; ++e) {
      const Index j = i + offset(gen);
      if (j >= n) continue;
      const double k = -value(gen);
      t.emplace_back(int(i), int(j), k);
      t.emplace_back(int(j), int(i), k);
      row += 2.0 * std::abs(k);
    }
    t.emplace_back(int(i), int(i), 4.0 + row);
  }
  SparseMatrix A(n, n);
  A.setFromTriplets(t.begin(), t.end());  // (duplicates summed)
  A.makeCompressed();
  return A;
}

// The rayleigh and shared forms of LinearProduct: which form is chosen for which C, and that each
// gives the rows' sums to round-off. The bound per row is 8 eps (|out0| + |K| |u| + |C| |v|): a sum
// of a few dozen terms, each rounded once or twice, in another order.
void linear_product_reordered_cases() {
  std::mt19937 gen(31415);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> mass(0.5, 4.0);
  using Form = nvib::LinearProduct::Form;
  int cases = 0;
  double worst = 0.0;
  for (Index n : {17, 700}) {  // (17: below kReorderFrom, the rows' sums)
    const SparseMatrix K = scattered_symmetric(n, gen);
    Vector m(n), u(n), v(n), out0(n);
    for (Index i = 0; i < n; ++i) m[i] = mass(gen), u[i] = normal(gen), v[i] = normal(gen), out0[i] = normal(gen);
    SparseMatrix Mlump(n, n);
    for (Index i = 0; i < n; ++i) Mlump.insert(i, i) = m[i];
    auto check = [&](const SparseMatrix& C, bool lumped, Form expected, const char* what) {
      if (K.nonZeros() + C.nonZeros() < nvib::LinearProduct::kReorderFrom) expected = Form::rows;
      const nvib::LinearProduct p(K, C, lumped ? &m : nullptr);
      if (p.form() != expected) std::printf("  %s (n = %lld): form %s\n", what, (long long)n, p.form_name());
      CHECK(p.form() == expected);
      Vector out = out0;
      p.add(u.data(), v.data(), out.data());
      const Vector ref = rows_reference(K, C, u, v, out0);
      if (expected == Form::rows) CHECK(bitwise_equal(out, ref));
      const Vector mag = out0.cwiseAbs() + SparseMatrix(K.cwiseAbs()) * u.cwiseAbs() + SparseMatrix(C.cwiseAbs()) * v.cwiseAbs();
      for (Index i = 0; i < n; ++i) {
        const double e = std::abs(out[i] - ref[i]) / (std::numeric_limits<double>::epsilon() * mag[i]);
        worst = std::max(worst, e);
        CHECK(e <= 8.0);
      }
      // with a scratch (the model's add_linear): the same bits; the scratch is taken by rayleigh alone
      {
        Vector formed = out0, scratch = Vector::Constant(n, std::numeric_limits<double>::quiet_NaN());
        p.add(u.data(), v.data(), formed.data(), scratch.data());
        CHECK(bitwise_equal(formed, out));
        CHECK(p.uses_scratch() == (p.form() == Form::rayleigh));
        CHECK(p.uses_scratch() == !std::isnan(scratch[n - 1]));
      }
      // a range of rows gives those rows of the whole
      if (n > 4) {
        Vector part = out0;
        p.add(u.data(), v.data(), part.data(), 2, n - 1);
        CHECK(bitwise_equal(part.segment(2, n - 3), out.segment(2, n - 3)));
        CHECK(part[0] == out0[0] && part[1] == out0[1] && part[n - 1] == out0[n - 1]);
      }
      ++cases;
    };
    const double alpha = 0.37, beta = 2.3e-3;
    const SparseMatrix C = SparseMatrix(alpha * Mlump) + SparseMatrix(beta * K);  // as an engineer assembles it
    check(C, true, Form::rayleigh, "Rayleigh, lumped");
    if (n > 17) {
      const nvib::LinearProduct p(K, C, &m);
      CHECK(std::abs(p.rayleigh_alpha() - alpha) <= 1e-14 * alpha && std::abs(p.rayleigh_beta() - beta) <= 1e-14 * beta);
    }
    check(SparseMatrix(beta * K), true, Form::rayleigh, "stiffness-proportional");
    check(SparseMatrix(alpha * Mlump), true, Form::rayleigh, "mass-proportional");
    check(C, false, Form::shared, "Rayleigh, mass not lumped");  // K's pattern (its diagonal is full)
    SparseMatrix off = C;  // one entry 1e-9 off the form: not Rayleigh, still K's pattern
    off.coeffRef(0, 0) *= 1.0 + 1e-9;
    check(off, true, Form::shared, "Rayleigh plus 1e-9 in one entry");
    SparseMatrix damper(n, n);  // one damper between DOFs 0 and n - 1: not K's pattern
    damper.insert(0, 0) = 3.0, damper.insert(n - 1, n - 1) = 3.0;
    if (n > 1) damper.insert(0, n - 1) = -3.0, damper.insert(n - 1, 0) = -3.0;
    check(damper, true, Form::rows, "one damper");
  }
  std::printf("LinearProduct rayleigh / shared: %d cases, within %.1f eps of the rows' sums\n", cases, worst);
}

// A mesh-like pattern of nodes of B DOFs: each node coupled to a few nodes within +-6 by a full B x B
// block, except that `holes` of each coupling block's off-diagonal positions are left out (a brick
// mesh's blocks hold some exact zeros).
SparseMatrix node_pattern(Index nodes, int B, int holes, std::mt19937& gen) {
  std::uniform_int_distribution<int> offset(1, 6), pick(0, B * B - 1);
  std::uniform_real_distribution<double> value(-1.0, 1.0);
  std::vector<Eigen::Triplet<double, int>> t;
  auto block = [&](Index a, Index b, bool full) {
    std::vector<bool> keep(static_cast<size_t>(B * B), true);
    for (int h = 0; h < holes && !full; ++h) keep[static_cast<size_t>(pick(gen))] = false;
    for (int r = 0; r < B; ++r)
      for (int c = 0; c < B; ++c)
        if (keep[static_cast<size_t>(r * B + c)]) {
          const double x = value(gen);
          t.emplace_back(int(B * a + r), int(B * b + c), x);
          t.emplace_back(int(B * b + c), int(B * a + r), x);
        }
  };
  for (Index k = 0; k < nodes; ++k) {
    block(k, k, true);
    for (int e = 0; e < 3; ++e) {
      const Index other = k + offset(gen);
      if (other < nodes) block(k, other, false);
    }
  }
  SparseMatrix A(B * nodes, B * nodes);
  A.setFromTriplets(t.begin(), t.end());
  for (Index i = 0; i < A.rows(); ++i) A.coeffRef(i, i) += 40.0;
  A.makeCompressed();
  return A;
}

// The rayleigh and shared forms on node blocks (LinearProduct::node_block()): taken for nodes of 3 and 2
// DOFs whose blocks are nearly full, not where they are not; every way of taking them (whole, with a
// scratch, in pieces of rows across the blocks) gives the bits of the rows' sums: out0 + sum over K's
// stored columns, ascending, of K_ij (u_j + beta v_j), then + alpha m_i v_i (rayleigh), or of
// K_ij u_j + C_ij v_j (shared).
void linear_product_node_blocks() {
  std::mt19937 gen(2718);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> mass(0.5, 4.0);
  int cases = 0;
  for (int B : {3, 2})
    for (int holes : {0, 1, 6}) {
      const SparseMatrix K = node_pattern(900 / B, B, holes, gen);
      const Index n = K.rows();
      Vector m(n), u(n), v(n), out0(n);
      for (Index i = 0; i < n; ++i) m[i] = mass(gen), u[i] = normal(gen), v[i] = normal(gen), out0[i] = normal(gen);
      SparseMatrix Mlump(n, n);
      for (Index i = 0; i < n; ++i) Mlump.insert(i, i) = m[i];
      const SparseMatrix C = SparseMatrix(0.37 * Mlump) + SparseMatrix(2.3e-3 * K);
      const nvib::LinearProduct p(K, C, &m);
      CHECK(p.form() == nvib::LinearProduct::Form::rayleigh);
      // the blocks' share of K's entries decides
      long blocks = 0;
      {
        std::set<std::pair<Index, Index>> seen;
        for (Index j = 0; j < K.outerSize(); ++j)
          for (SparseMatrix::InnerIterator it(K, j); it; ++it) seen.insert({it.row() / B, it.col() / B});
        blocks = static_cast<long>(seen.size());
      }
      const bool blocked = double(blocks) * B * B <= nvib::LinearProduct::kMaxPadding * double(K.nonZeros());
      if (p.node_block() != (blocked ? B : 0))
        std::printf("  B = %d, holes %d: node_block() %d, padding %.3f\n", B, holes, p.node_block(), double(blocks) * B * B / double(K.nonZeros()));
      CHECK(p.node_block() == (blocked ? B : 0));
      const nvib::LinearProduct::RowMatrix Kr = K;
      const double alpha = p.rayleigh_alpha(), beta = p.rayleigh_beta();
      const Vector am = alpha * m;
      Vector ref(n);
      for (Index i = 0; i < n; ++i) {
        double s = out0[i];
        for (nvib::LinearProduct::RowMatrix::InnerIterator it(Kr, i); it; ++it) s += it.value() * (u[it.col()] + beta * v[it.col()]);
        ref[i] = s + am[i] * v[i];
      }
      Vector out = out0;
      p.add(u.data(), v.data(), out.data());
      CHECK(bitwise_equal(out, ref));
      Vector formed = out0, scratch(n);
      p.add(u.data(), v.data(), formed.data(), scratch.data());
      CHECK(bitwise_equal(formed, ref));
      Vector pieces = out0;
      for (Index r0 = 0; r0 < n; r0 += 37) p.add(u.data(), v.data(), pieces.data(), r0, std::min(n, r0 + 37));
      CHECK(bitwise_equal(pieces, ref));
      cases += blocked;
      // the shared form (C on K's pattern, another mass): the rows' sums of K_ij u_j + C_ij v_j
      SparseMatrix Cs = K;
      for (Index j = 0; j < Cs.outerSize(); ++j)
        for (SparseMatrix::InnerIterator it(Cs, j); it; ++it) it.valueRef() = normal(gen);
      const nvib::LinearProduct ps(K, Cs, nullptr);
      CHECK(ps.form() == nvib::LinearProduct::Form::shared);
      CHECK(ps.node_block() == (blocked ? B : 0));
      const nvib::LinearProduct::RowMatrix Csr = Cs;
      Vector sref(n);
      for (Index i = 0; i < n; ++i) {
        double s = out0[i];
        nvib::LinearProduct::RowMatrix::InnerIterator c(Csr, i);
        for (nvib::LinearProduct::RowMatrix::InnerIterator k(Kr, i); k; ++k, ++c) s += k.value() * u[k.col()] + c.value() * v[c.col()];
        sref[i] = s;
      }
      Vector sout = out0;
      ps.add(u.data(), v.data(), sout.data());
      CHECK(bitwise_equal(sout, sref));
      Vector spieces = out0;
      for (Index r0 = 0; r0 < n; r0 += 37) ps.add(u.data(), v.data(), spieces.data(), r0, std::min(n, r0 + 37));
      CHECK(bitwise_equal(spieces, sref));
      Vector sone = out0;  // a piece inside one block row, and one that ends inside the next
      ps.add(u.data(), v.data(), sone.data(), 1, 2);
      ps.add(u.data(), v.data(), sone.data(), 2, B + 1);
      CHECK(bitwise_equal(sone.segment(1, B), sref.segment(1, B)));
      CHECK(sone[0] == out0[0] && sone[B + 1] == out0[B + 1]);
    }
  std::printf("LinearProduct node blocks: %d blocked cases, bit for bit with the rows' rayleigh and shared sums\n", cases);
  CHECK(cases >= 2);
}

}  // namespace

int main() {
  linear_product_cases();
  linear_product_reordered_cases();
  linear_product_node_blocks();
  using LS = nvib::LinearSolverChoice;
  using Mode = nvib::NewtonMode;
  const Index n = 120;
  const auto model = fx::make_effect_model(nvib::Mass::diagonal(Vector::LinSpaced(n, 1.0, 2.0)), chain(n));
  CHECK(model.has_sparse_tangent() && model.has_C() && !model.has_K());

  for (Mode mode : {Mode::newton, Mode::modified, Mode::incremental, Mode::one_iteration}) {
    const std::string m = nvib::to_string(mode);
    same_with_both_solvers(("Newmark, chain, " + m).c_str(), model, nvib::Newmark(0.25, 0.5, with_solver(mode, LS::dense)),
                           nvib::Newmark(0.25, 0.5, with_solver(mode, LS::sparse)), "sparse LDLT");
    same_with_both_solvers(("GeneralizedAlpha(rho 0.8), chain, " + m).c_str(), model,
                           nvib::GeneralizedAlpha::from_rho_inf(0.8, with_solver(mode, LS::dense)),
                           nvib::GeneralizedAlpha::from_rho_inf(0.8, with_solver(mode, LS::sparse)), "sparse LDLT");
    same_with_both_solvers(("Newmark, chain, " + m).c_str(), model, nvib::Newmark(0.25, 0.5, with_solver(mode, LS::dense)),
                           nvib::Newmark(0.25, 0.5, with_solver(mode, LS::banded)), "banded LDLT");
    // Up to 64 DOFs (the dense LU's unblocked elimination) too
    const auto small = fx::make_effect_model(nvib::Mass::diagonal(Vector::LinSpaced(40, 1.0, 2.0)), chain(40));
    same_with_both_solvers(("Newmark, chain of 40, " + m).c_str(), small, nvib::Newmark(0.25, 0.5, with_solver(mode, LS::dense)),
                           nvib::Newmark(0.25, 0.5, with_solver(mode, LS::banded)), "banded LDLT");
    same_with_both_solvers(("GeneralizedAlpha(rho 0.8), chain of 40, " + m).c_str(), small,
                           nvib::GeneralizedAlpha::from_rho_inf(0.8, with_solver(mode, LS::dense)),
                           nvib::GeneralizedAlpha::from_rho_inf(0.8, with_solver(mode, LS::banded)), "banded LDLT");
  }
  // The sparse assembly of S sums K_t, C_t, the mass and the linear parts in the dense assembly's order:
  // the same S, bit for bit (chain: nonlinear springs, linear dampers; with a linear K and a consistent
  // mass too).
  {
    SparseMatrix Kl(n, n), Ms(n, n);
    for (Index i = 0; i + 1 < n; ++i) Kl.insert(i, i + 1) = Kl.insert(i + 1, i) = -30.0 - double(i);
    for (Index i = 0; i < n; ++i) {
      Kl.insert(i, i) = 100.0;
      Ms.insert(i, i) = 4.0;
      if (i + 1 < n) Ms.insert(i, i + 1) = Ms.insert(i + 1, i) = 1.0;
    }
    auto lumped = fx::make_effect_model(nvib::Mass::diagonal(Vector::LinSpaced(n, 1.0, 2.0)), chain(n));
    auto consistent = fx::make_effect_model(nvib::Mass::sparse(Ms), chain(n), Kl);
    auto same_S = [&](auto& model) {
      const Vector u = Vector::LinSpaced(n, -0.02, 0.03), v = Vector::LinSpaced(n, 0.5, -0.4);
      const nvib::IterationMatrix im{4e6, 2e3, 0.7, &u, &v, 0.3};
      nvib::Stats st;
      nvib::SparseIterationMatrix sparse_S;
      sparse_S.setup(model);
      CHECK(sparse_S.assemble(model, im, st));
      nvib::DenseIterationMatrix dense_S;
      Matrix D = Matrix::Zero(n, n);
      dense_S.assemble(model, im, st, false, D);
      const SparseMatrix& S = sparse_S.matrix();
      bool same = true;
      for (Index j = 0; j < n; ++j)
        for (SparseMatrix::InnerIterator it(S, j); it; ++it) same = same && it.value() == D(it.row(), j);
      CHECK(same && Matrix(S) == D);
    };
    same_S(lumped);
    same_S(consistent);
  }
  // The automatic choice: a chain's band at every size; a long-range coupling spoils the band: dense LU
  // up to 64 DOFs, sparse LDL^T above.
  {
    const Vector u0 = Vector::Zero(n), v0 = Vector::Zero(n);
    CHECK(std::string(nvib::solve(model, nvib::Newmark(), 1e-3, 0.01, u0, v0).stats.linear_solver) == "banded LDLT");
    const auto small = fx::make_effect_model(nvib::Mass::diagonal(Vector::Ones(10)), chain(10));
    CHECK(std::string(nvib::solve(small, nvib::Newmark(), 1e-3, 0.01, Vector::Zero(10), Vector::Zero(10))
                          .stats.linear_solver) == "banded LDLT");
    for (Index size : {Index(10), n}) {
      auto list = chain(size);
      list.push_back(fx::hardening_spring({{0, 1.0}, {size - 1, -1.0}}, 1e3, 5.0));  // end to end
      const auto ring = fx::make_effect_model(nvib::Mass::diagonal(Vector::Ones(size)), std::move(list));
      CHECK(std::string(nvib::solve(ring, nvib::Newmark(), 1e-3, 0.01, Vector::Zero(size), Vector::Zero(size))
                            .stats.linear_solver) == (size <= 64 ? "dense LU" : "sparse LDLT"));
    }
  }
  // A large linear model with a few nonlinear effects (a 20 x 20 grid of linear springs and dampers,
  // hardening springs and a power-law damper at four DOFs): the linear part factorised once and the
  // effects' tangent as a low-rank update, chosen automatically; the trajectories of the sparse
  // factorisation of S every iteration, to round-off, with as many Newton iterations, in every mode.
  // A static problem whose linear part holds no DOF on its own falls back to factorising S.
  {
    const Index side = 20, N = side * side;
    std::vector<fx::Effect> list;
    for (Index r = 0; r < side; ++r)
      for (Index c = 0; c < side; ++c) {
        const Index i = r * side + c;
        if (c + 1 < side) list.push_back(fx::spring({{i, 1.0}, {i + 1, -1.0}}, 2e3 + double(i)));
        if (r + 1 < side) list.push_back(fx::spring({{i, 1.0}, {i + side, -1.0}}, 1.5e3));
        if (r == 0) list.push_back(fx::spring({{i, 1.0}}, 4e3));
        list.push_back(fx::damper({{i, 1.0}}, 0.5));
      }
    list.push_back(fx::hardening_spring({{N - 1, 1.0}}, 1e3, 400.0));
    list.push_back(fx::hardening_spring({{N - side, 1.0}, {N - side - 1, -1.0}}, 2e3, 300.0));
    list.push_back(fx::hardening_spring({{side * 10 + 3, 1.0}}, 5e2, 800.0));
    list.push_back(fx::power_damper({{N - 1, 1.0}, {N / 2, -1.0}}, 3.0, 1.5));
    fx::Measure r;
    for (Index i = 0; i < N; ++i) r.emplace_back(i, 1.0);
    list.push_back(fx::ground_acceleration(r, fx::Signal::sine(30.0, 25.0)));
    const auto grid = fx::make_effect_model(nvib::Mass::diagonal(Vector::LinSpaced(N, 1.0, 1.5)), std::move(list));
    const Vector u0 = Vector::Zero(N), v0 = Vector::Zero(N);
    for (Mode mode : {Mode::newton, Mode::modified, Mode::incremental, Mode::one_iteration}) {
      const auto a = nvib::solve(grid, nvib::Newmark(0.25, 0.5, with_solver(mode, LS::sparse)), 2e-3, 0.4, u0, v0);
      const auto b = nvib::solve(grid, nvib::Newmark(0.25, 0.5, with_solver(mode, LS::automatic)), 2e-3, 0.4, u0, v0);
      const auto c = nvib::solve(grid, nvib::GeneralizedAlpha::from_rho_inf(0.7, with_solver(mode, LS::low_rank)),
                                 2e-3, 0.4, u0, v0);
      const auto d = nvib::solve(grid, nvib::GeneralizedAlpha::from_rho_inf(0.7, with_solver(mode, LS::sparse)),
                                 2e-3, 0.4, u0, v0);
      CHECK(a.status == nvib::Status::success && b.status == nvib::Status::success);
      CHECK(c.status == nvib::Status::success && d.status == nvib::Status::success);
      const std::string base = a.stats.linear_solver;  // (supernodal or simplicial by its fill)
      CHECK(base == "sparse LDLT" || base == "supernodal LDLT");
      CHECK(std::string(b.stats.linear_solver) == base + " + low-rank update");
      CHECK(std::string(c.stats.linear_solver) == base + " + low-rank update");
      if (mode == Mode::newton) std::printf("grid: %s\n", b.stats.linear_solver);
      const double du = rel_diff(b.u, a.u), dv = rel_diff(b.v, a.v), du2 = rel_diff(c.u, d.u);
      std::printf("grid %lld DOFs + 4 nonlinear effects, %-13s low-rank vs sparse: u %.1e v %.1e (GaM u %.1e), "
                  "Newton it. %lld / %lld, max |u| %.3g\n",
                  static_cast<long long>(N), nvib::to_string(mode), du, dv, du2,
                  static_cast<long long>(b.stats.num_newton_iters), static_cast<long long>(a.stats.num_newton_iters),
                  b.u.cwiseAbs().maxCoeff());
      CHECK(du <= 1e-11 && dv <= 1e-11 && du2 <= 1e-11);
      CHECK(b.stats.num_newton_iters == a.stats.num_newton_iters);
      CHECK(c.stats.num_newton_iters == d.stats.num_newton_iters);
    }
    // The springs matter (hardening: the answer is not the linear one).
    {
      const auto b = nvib::solve(grid, nvib::Newmark(), 2e-3, 0.4, u0, v0);
      CHECK(b.stats.num_newton_iters > b.stats.num_steps);
    }
    // Static: no linear stiffness holds DOF 0 of this model (its only spring is nonlinear), so the linear
    // part is singular and S itself is factorised; the answer is that of the sparse solver.
    {
      std::vector<fx::Effect> two;
      for (Index i = 0; i + 1 < 200; ++i) two.push_back(fx::spring({{i, 1.0}, {i + 1, -1.0}}, 1e3));
      two.push_back(fx::hardening_spring({{0, 1.0}}, 1e3, 10.0));
      two.push_back(fx::constant_force({{199, 1.0}}, 50.0));
      two.push_back(fx::hardening_spring({{0, 1.0}, {150, -1.0}}, 1e2, 10.0));  // off the band: sparse, not banded
      auto stat = fx::make_effect_model(nvib::Mass::diagonal(Vector::Ones(200)), std::move(two));
      const Vector x = nvib::static_equilibrium(stat, 0.0, Vector::Zero(200));
      CHECK(x.allFinite() && std::abs(x[0]) > 0.0);
    }
  }
  // A nonsymmetric linear stiffness (a follower-type coupling): sparse LU.
  {
    SparseMatrix K(n, n);
    for (Index i = 0; i + 1 < n; ++i) K.insert(i, i + 1) = 300.0;
    const auto follower = fx::make_effect_model(nvib::Mass::diagonal(Vector::Ones(n)), chain(n), K);
    same_with_both_solvers("Newmark, chain + nonsymmetric K", follower,
                           nvib::Newmark(0.25, 0.5, with_solver(Mode::newton, LS::dense)),
                           nvib::Newmark(0.25, 0.5, with_solver(Mode::newton, LS::sparse)), "sparse LU");
  }
  // A consistent (tridiagonal) mass, sparse and dense: explicit and implicit schemes agree to round-off.
  {
    SparseMatrix Ms(n, n);
    for (Index i = 0; i < n; ++i) {
      Ms.insert(i, i) = 4.0;
      if (i + 1 < n) Ms.insert(i, i + 1) = Ms.insert(i + 1, i) = 1.0;
    }
    const auto ms = fx::make_effect_model(nvib::Mass::sparse(Ms), chain(n));
    const auto md = fx::make_effect_model(nvib::Mass::dense(Matrix(Ms)), chain(n));
    CHECK(ms.mass().kind() == nvib::Mass::Kind::sparse && md.mass().kind() == nvib::Mass::Kind::dense);
    const Vector u0 = Vector::Constant(n, 1e-3), v0 = Vector::Zero(n);
    const auto a = nvib::solve(ms, nvib::CentralDifference(), 1e-4, 0.05, u0, v0);
    const auto b = nvib::solve(md, nvib::CentralDifference(), 1e-4, 0.05, u0, v0);
    std::printf("consistent mass, sparse vs dense, CentralDifference: u %.1e\n", rel_diff(a.u, b.u));
    CHECK(rel_diff(a.u, b.u) <= 1e-12 && rel_diff(a.v, b.v) <= 1e-12);
    const auto c = nvib::solve(ms, nvib::Newmark(), 1e-3, 0.2, u0, v0);
    const auto d = nvib::solve(md, nvib::Newmark(0.25, 0.5, with_solver(Mode::newton, LS::dense)), 1e-3, 0.2, u0, v0);
    std::printf("consistent mass, sparse vs dense, Newmark (%s vs %s): u %.1e\n", c.stats.linear_solver,
                d.stats.linear_solver, rel_diff(c.u, d.u));
    CHECK(std::string(c.stats.linear_solver) == "banded LDLT");  // a tridiagonal mass keeps the band
    CHECK(rel_diff(c.u, d.u) <= 1e-12 && rel_diff(c.v, d.v) <= 1e-12);
    // A mass with only diagonal entries given as sparse is lumped.
    SparseMatrix Dg(3, 3);
    Dg.insert(0, 0) = 1.0;
    Dg.insert(1, 1) = 2.0;
    Dg.insert(2, 2) = 3.0;
    CHECK(nvib::Mass::sparse(Dg).is_diagonal());
  }
  // Bad masses are named.
  {
    SparseMatrix bad(2, 2);
    bad.insert(0, 0) = 1.0;
    bad.insert(0, 1) = 2.0;
    bad.insert(1, 1) = 1.0;
    bool named = false;
    try {
      nvib::Mass::sparse(bad);
    } catch (const nvib::ArgumentError& e) {
      named = e.argument() == "mass" && std::string(e.what()).find("not symmetric") != std::string::npos;
    }
    CHECK(named);
    named = false;
    try {
      nvib::Mass::dense(Matrix::Identity(nvib::Mass::kDenseMax + 1, nvib::Mass::kDenseMax + 1));
    } catch (const nvib::ArgumentError& e) {
      named = e.argument() == "mass" && std::string(e.what()).find("sparse") != std::string::npos;
    }
    CHECK(named);
  }
  // A mass that fails its factorisation names the DOF and whether its pivot is zero or negative; a
  // nearly singular one is accepted with a warning naming the DOF.
  {
    auto message = [](auto&& make) {
      try {
        make();
      } catch (const nvib::ArgumentError& e) {
        return e.argument() + "|" + e.what();
      }
      return std::string();
    };
    Matrix singular{{1.0, 1.0, 0.0}, {1.0, 1.0, 0.0}, {0.0, 0.0, 1.0}};
    const std::string s1 = message([&] { nvib::Mass::dense(singular); });
    CHECK(s1.find("mass|") == 0 && s1.find("singular: the pivot of DOF 1 after eliminating") != std::string::npos);
    const std::string s2 = message([&] { nvib::Mass::sparse(singular.sparseView()); });
    CHECK(s2.find("the sparse mass matrix is not positive definite: it is singular: the pivot of DOF 1") != std::string::npos);
    Matrix indefinite{{1.0, 2.0}, {2.0, 1.0}};
    const std::string s3 = message([&] { nvib::Mass::dense(indefinite, [](Index i) { return "node " + std::to_string(i); }); });
    CHECK(s3.find("indefinite: the pivot of node 1 after eliminating the DOFs before it is -3 < 0") != std::string::npos);
    Matrix nearly{{1.0, 1.0}, {1.0, 1.0 + 1e-14}};
    CHECK(nvib::Mass::dense(nearly).warning().find("the mass matrix is nearly singular: the Cholesky pivot of DOF 1") == 0);
    CHECK(nvib::Mass::dense(Matrix::Identity(2, 2)).warning().empty());
    const auto model = nvib::make_linear_model(nvib::Mass::dense(nearly), Matrix::Identity(2, 2));
    CHECK(model.warnings().size() == 1 && model.warnings()[0].find("mass: the mass matrix is nearly singular") == 0);
  }
  // One triangle of a symmetric K with its diagonal is refused naming K; a one-sided coupling without a
  // diagonal, with grounded springs added by the effects, is not.
  {
    Matrix full{{2.0, -1.0}, {-1.0, 2.0}};
    bool named = false;
    try {
      nvib::make_linear_model(nvib::Mass::diagonal(Vector::Ones(2)), Matrix(full.triangularView<Eigen::Upper>()));
    } catch (const nvib::ArgumentError& e) {
      named = e.argument() == "K" && std::string(e.what()).find("one triangle") != std::string::npos;
    }
    CHECK(named);
    Matrix coupling{{0.0, 1.0}, {0.0, 0.0}};
    std::vector<fx::Effect> springs{fx::spring({{0, 1.0}}, 10.0), fx::spring({{1, 1.0}}, 10.0)};
    const auto follower = fx::make_effect_model(nvib::Mass::diagonal(Vector::Ones(2)), springs, coupling);
    CHECK(follower.K().coeff(0, 0) == 10.0 && follower.K().coeff(0, 1) == 1.0);
  }
  // The default divergence bound follows the static displacement of the loads: 2e11 here (a model in
  // nm loaded to 200 m), so a stable run of it is not called diverged.
  {
    std::vector<fx::Effect> load{fx::constant_force({{0, 1.0}}, 200.0)};
    const auto nm = fx::make_effect_model(nvib::Mass::diagonal(Vector::Constant(1, 1e-9)), load,
                                          Matrix(Matrix::Constant(1, 1, 1e-9)), Matrix(Matrix::Constant(1, 1, 2e-10)));
    const double scale = nvib::load_displacement_scale(nm, 0.0, 20.0);
    CHECK(std::abs(scale - 200.0 / (1e-9 + 1e-9 / 400.0)) <= 1e-9 * scale);
    const auto res = nvib::solve(nm, nvib::CentralDifference(), 0.05, 20.0, Vector::Zero(1), Vector::Zero(1));
    CHECK(res.status == nvib::Status::success && res.u.cwiseAbs().maxCoeff() > 1e10);
  }
  // Static equilibrium of the chain under a constant load on its last DOF: sparse and dense agree.
  {
    auto list = chain(n);
    list.pop_back();  // no ground motion
    list.push_back(fx::constant_force({{n - 1, 1.0}}, 500.0));
    auto loaded = fx::make_effect_model(nvib::Mass::diagonal(Vector::Ones(n)), list);
    const Vector u = nvib::static_equilibrium(loaded, 0.0, Vector::Zero(n));
    Vector f(n);
    nvib::Stats st;
    loaded.force(u, Vector::Zero(n), 0.0, f, st);
    std::printf("static equilibrium of the loaded chain: max |residual| %.1e N, u_end %.6g\n",
                f.cwiseAbs().maxCoeff(), u[n - 1]);
    CHECK(f.cwiseAbs().maxCoeff() <= 1e-9 * 500.0);
  }
  return nvib_test::finish("test_sparse");
}
