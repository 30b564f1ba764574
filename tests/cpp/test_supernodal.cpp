// SupernodalCholesky (LL^T and unpivoted LDL^T) against Eigen's simplicial factorisations of the same
// permuted matrix: the factors and pivots to round-off, relative residuals of the solve at round-off,
// on small and structured matrices, Laplacians, a random SPD matrix and a 3-D elastic solid (trilinear
// hexahedra, stiffness plus consistent mass), with the automatic ordering and with AMD and nested
// dissection forced (also on a matrix of two components and one with no edges); an upper triangle
// stored and ignored; refactorisation on the same pattern; indefinite and singular matrices; the
// symbolic counts against the simplicial factor's; nested dissection's flops on a 3-D solid; and no
// heap allocation in factorize_values() and solve_in_place().
#include "counting_new.hpp"  // first: it sets up Eigen's allocation check

#include <nvib/linalg/sparse_cholesky.hpp>
#include <nvib/linalg/supernodal_cholesky.hpp>

#include <Eigen/SparseCholesky>

#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "check.hpp"

using nvib::Index;
using nvib::Matrix;
using nvib::SparseMatrix;
using nvib::Vector;
using Triplets = std::vector<Eigen::Triplet<double, int>>;

namespace {

SparseMatrix from_triplets(Index n, const Triplets& t) {
  SparseMatrix A(n, n);
  A.setFromTriplets(t.begin(), t.end());
  A.makeCompressed();
  return A;
}

SparseMatrix symmetric_of(const SparseMatrix& lower) {
  SparseMatrix F(lower.rows(), lower.cols());
  F = lower.selfadjointView<Eigen::Lower>();
  return F;
}

// The lower triangle of a diagonally dominant stencil matrix on an nx x ny x nz grid (nz = 1: 2-D),
// `dofs` unknowns a node coupled to every unknown of the neighbouring nodes (the 5/7-point star when
// star, else the 9/27-point box); shift is subtracted from the diagonal (shifted into the spectrum, it
// makes the matrix indefinite).
SparseMatrix grid_matrix(int nx, int ny, int nz, bool star, int dofs, std::mt19937& gen, double shift = 0.0) {
  std::uniform_real_distribution<double> u(0.5, 1.0);
  auto node = [&](int i, int j, int k) { return (k * ny + j) * nx + i; };
  const Index n = static_cast<Index>(nx) * ny * nz * dofs;
  Triplets t;
  std::vector<double> diag(static_cast<size_t>(n), 0.0);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        for (int dk = (nz > 1 ? -1 : 0); dk <= (nz > 1 ? 1 : 0); ++dk)
          for (int dj = -1; dj <= 1; ++dj)
            for (int di = -1; di <= 1; ++di) {
              const int a = i + di, b = j + dj, c = k + dk;
              if (a < 0 || b < 0 || c < 0 || a >= nx || b >= ny || c >= nz) continue;
              if (star && std::abs(di) + std::abs(dj) + std::abs(dk) != 1) continue;
              if (!star && di == 0 && dj == 0 && dk == 0) continue;
              const int p = node(i, j, k), q = node(a, b, c);
              if (q >= p) continue;
              for (int r = 0; r < dofs; ++r)
                for (int s = 0; s < dofs; ++s) {
                  const double v = -u(gen);
                  const int row = p * dofs + r, col = q * dofs + s;
                  t.emplace_back(row, col, v);
                  diag[static_cast<size_t>(row)] += std::abs(v);
                  diag[static_cast<size_t>(col)] += std::abs(v);
                }
            }
  for (Index i = 0; i < n; ++i) {
    t.emplace_back(static_cast<int>(i), static_cast<int>(i), diag[static_cast<size_t>(i)] + 0.1 - shift);
    // the DOFs of a node coupled among themselves too
    for (int s = 0; s < static_cast<int>(i % dofs); ++s) t.emplace_back(static_cast<int>(i), static_cast<int>(i) - 1 - s, 0.01 * u(gen));
  }
  return from_triplets(n, t);
}

SparseMatrix tridiagonal(Index n) {
  Triplets t;
  for (Index i = 0; i < n; ++i) {
    t.emplace_back(static_cast<int>(i), static_cast<int>(i), 2.0 + 1e-3);
    if (i > 0) t.emplace_back(static_cast<int>(i), static_cast<int>(i - 1), -1.0);
  }
  return from_triplets(n, t);
}

SparseMatrix random_spd(Index n, double density, std::mt19937& gen) {
  std::uniform_real_distribution<double> u(-1.0, 1.0), coin(0.0, 1.0);
  Triplets t;
  std::vector<double> diag(static_cast<size_t>(n), 0.0);
  for (Index j = 0; j < n; ++j)
    for (Index i = j + 1; i < n; ++i)
      if (coin(gen) < density) {
        const double v = u(gen);
        t.emplace_back(static_cast<int>(i), static_cast<int>(j), v);
        diag[static_cast<size_t>(i)] += std::abs(v);
        diag[static_cast<size_t>(j)] += std::abs(v);
      }
  for (Index i = 0; i < n; ++i) t.emplace_back(static_cast<int>(i), static_cast<int>(i), diag[static_cast<size_t>(i)] + 1.0);
  return from_triplets(n, t);
}

// Stiffness and consistent mass (24 x 24) of a trilinear brick of edges h, 2 x 2 x 2 Gauss points.
void hexahedron(const std::array<double, 3>& h, double E, double nu, double rho, Matrix& Ke, Matrix& Me) {
  const double lam = E * nu / ((1 + nu) * (1 - 2 * nu)), mu = E / (2 * (1 + nu));
  Matrix D = Matrix::Zero(6, 6);
  D.topLeftCorner(3, 3).setConstant(lam);
  for (int i = 0; i < 3; ++i) D(i, i) += 2 * mu, D(i + 3, i + 3) = mu;
  const double corners[8][3] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1}, {-1, -1, 1}, {1, -1, 1}, {1, 1, 1}, {-1, 1, 1}};
  const double half[3] = {h[0] / 2, h[1] / 2, h[2] / 2}, det = half[0] * half[1] * half[2];
  const double g = 1.0 / std::sqrt(3.0);
  Ke = Matrix::Zero(24, 24);
  Me = Matrix::Zero(24, 24);
  for (double xi : {-g, g})
    for (double eta : {-g, g})
      for (double zeta : {-g, g}) {
        const double p[3] = {xi, eta, zeta};
        double N[8], dN[8][3];
        for (int a = 0; a < 8; ++a) {
          double f[3];
          for (int d = 0; d < 3; ++d) f[d] = 1 + corners[a][d] * p[d];
          N[a] = f[0] * f[1] * f[2] / 8;
          for (int d = 0; d < 3; ++d) dN[a][d] = corners[a][d] * f[(d + 1) % 3] * f[(d + 2) % 3] / 8 / half[d];
        }
        Matrix B = Matrix::Zero(6, 24), Nm = Matrix::Zero(3, 24);
        for (int a = 0; a < 8; ++a) {
          const double bx = dN[a][0], by = dN[a][1], bz = dN[a][2];
          B(0, 3 * a) = bx, B(1, 3 * a + 1) = by, B(2, 3 * a + 2) = bz;
          B(3, 3 * a) = by, B(3, 3 * a + 1) = bx;
          B(4, 3 * a + 1) = bz, B(4, 3 * a + 2) = by;
          B(5, 3 * a) = bz, B(5, 3 * a + 2) = bx;
          for (int d = 0; d < 3; ++d) Nm(d, 3 * a + d) = N[a];
        }
        Ke += B.transpose() * D * B * det;
        Me += rho * Nm.transpose() * Nm * det;
      }
}

// The lower triangle of K + c M of an nx x ny x nz block of bricks clamped at z = 0 (3 DOFs a node).
SparseMatrix elastic_block(int nx, int ny, int nz, double c) {
  Matrix Ke, Me;
  hexahedron({1.0, 1.0, 1.0}, 3e10, 0.2, 2500.0, Ke, Me);
  const Matrix Se = Ke + c * Me;
  auto node = [&](int i, int j, int k) { return (k * (ny + 1) + j) * (nx + 1) + i; };
  const int clamped = (nx + 1) * (ny + 1);
  const Index n = 3 * (static_cast<Index>((nx + 1) * (ny + 1) * (nz + 1)) - clamped);
  Triplets t;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const int cn[8] = {node(i, j, k), node(i + 1, j, k), node(i + 1, j + 1, k), node(i, j + 1, k),
                           node(i, j, k + 1), node(i + 1, j, k + 1), node(i + 1, j + 1, k + 1), node(i, j + 1, k + 1)};
        for (int a = 0; a < 24; ++a)
          for (int b = 0; b < 24; ++b) {
            const int ra = 3 * (cn[a / 3] - clamped) + a % 3, rb = 3 * (cn[b / 3] - clamped) + b % 3;
            if (ra < 0 || rb < 0 || ra < rb) continue;
            t.emplace_back(ra, rb, Se(a, b));
          }
      }
  return from_triplets(n, t);
}

double residual(const SparseMatrix& full, const Vector& x, const Vector& b) {
  return (full * x - b).norm() / (full.norm() * x.norm());
}

// P A P^T of a full symmetric matrix, p: row of A -> row of P A P^T.
SparseMatrix permuted(const SparseMatrix& full, const std::vector<int>& p) {
  Triplets t;
  for (Index j = 0; j < full.outerSize(); ++j)
    for (SparseMatrix::InnerIterator it(full, j); it; ++it)
      t.emplace_back(p[static_cast<size_t>(it.row())], p[static_cast<size_t>(j)], it.value());
  return from_triplets(full.rows(), t);
}

// Factorise `stored` (whose lower triangle is that of the symmetric `full`) with both variants and check
// them against Eigen's simplicial factorisations of the same P A P^T (failures are recorded by CHECK).
void check_matrix(const std::string& name, const SparseMatrix& stored, const SparseMatrix& full, bool spd,
                  double tol = 1e-12, nvib::SupernodalOrdering ordering = nvib::SupernodalOrdering::automatic) {
  const Index n = full.rows();
  std::mt19937 gen(7);
  std::normal_distribution<double> normal(0.0, 1.0);
  Vector b(n);
  for (Index i = 0; i < n; ++i) b[i] = normal(gen);
  auto both = [&](auto tag) {
    constexpr bool LDLT = decltype(tag)::value;
    nvib::SupernodalCholesky<LDLT> f;
    f.ordering = ordering;
    f.analyze(stored);
    f.factorize_values(stored);
    if (!spd && !LDLT) {
      CHECK(f.info() == Eigen::NumericalIssue);
      return;
    }
    CHECK(f.info() == Eigen::Success);
    if (f.info() != Eigen::Success) {
      std::printf("%s (%s): factorisation failed\n", name.c_str(), LDLT ? "LDLT" : "LLT");
      return;
    }
    // The solve.
    Vector x = b, work(n);
    f.solve_in_place(x.data(), work);
    const double res = residual(full, x, b);
    if (!(res <= tol)) std::printf("%s (%s): residual %.3g\n", name.c_str(), LDLT ? "LDLT" : "LLT", res);
    CHECK(res <= tol);
    // The factors against Eigen's simplicial ones on the same permuted matrix.
    const SparseMatrix PA = permuted(full, f.permutation());
    const SparseMatrix L = f.matrix_l();
    SparseMatrix Le;
    Vector De;
    if constexpr (LDLT) {
      Eigen::SimplicialLDLT<SparseMatrix, Eigen::Lower, Eigen::NaturalOrdering<int>> ref(PA);
      CHECK(ref.info() == Eigen::Success);
      SparseMatrix strict = ref.matrixL().nestedExpression().template triangularView<Eigen::StrictlyLower>();
      SparseMatrix I(n, n);
      I.setIdentity();
      Le = strict + I;
      De = ref.vectorD();
      CHECK(f.simplicial_nonzeros() == ref.matrixL().nestedExpression().nonZeros() + n);
    } else {
      Eigen::SimplicialLLT<SparseMatrix, Eigen::Lower, Eigen::NaturalOrdering<int>> ref(PA);
      CHECK(ref.info() == Eigen::Success);
      Le = ref.matrixL().nestedExpression();
      De = Le.diagonal().cwiseAbs2();
      CHECK(f.simplicial_nonzeros() == Le.nonZeros());
    }
    const double dl = SparseMatrix(L - Le).norm() / Le.norm();
    if (!(dl <= tol)) std::printf("%s (%s): |L - L_eigen| / |L_eigen| = %.3g\n", name.c_str(), LDLT ? "LDLT" : "LLT", dl);
    CHECK(dl <= tol);
    CHECK((f.pivots() - De).norm() <= tol * De.norm());
    const Vector dp = f.dof_pivots();
    const double dmax = De.cwiseAbs().maxCoeff();
    for (Index i = 0; i < n; ++i) CHECK_CLOSE(dp[i], De[f.permutation()[static_cast<size_t>(i)]], tol * dmax);
    CHECK(f.nonzeros() >= f.simplicial_nonzeros());
    CHECK(f.flops() >= f.simplicial_flops());
    // Against OrderedCholesky, nvib's simplicial factorisation (its own AMD order).
    if (spd || LDLT) {
      nvib::OrderedCholesky<LDLT> o;
      o.analyze(stored);
      o.factorize_values(stored);
      Vector y = b;
      o.solve_in_place(y.data(), work);
      CHECK((x - y).norm() <= 1e3 * tol * y.norm());
    }
    // Without relaxation the supernodes are fundamental: no explicit zeros, so the supernodal counts
    // are the simplicial ones.
    nvib::SupernodalCholesky<LDLT> g;
    g.ordering = ordering;
    g.relaxation = nvib::SupernodeRelaxation{0, 0, 0.0, 0, 0.0, 0.0};
    g.analyze(stored);
    CHECK(g.nonzeros() == g.simplicial_nonzeros());
    CHECK(g.flops() == g.simplicial_flops());
    CHECK(g.simplicial_nonzeros() == f.simplicial_nonzeros() || ordering == nvib::SupernodalOrdering::automatic);
    g.factorize_values(stored);
    CHECK(g.info() == Eigen::Success);
    Vector z = b;
    g.solve_in_place(z.data(), work);
    CHECK(residual(full, z, b) <= tol);
  };
  both(std::false_type{});
  both(std::true_type{});
}

void check_lower(const std::string& name, const SparseMatrix& lower, bool spd = true, double tol = 1e-12,
                 nvib::SupernodalOrdering ordering = nvib::SupernodalOrdering::automatic) {
  check_matrix(name, lower, symmetric_of(lower), spd, tol, ordering);
}

// No allocation in factorize_values() and solve_in_place() after analyze() (and one warm-up).
template <bool LDLT>
void check_no_alloc(const std::string& name, const SparseMatrix& lower) {
  nvib::SupernodalCholesky<LDLT> f;
  f.analyze(lower);
  const Index n = lower.rows();
  Vector x = Vector::Ones(n), work(n);
  bool threw = false;
  g_news = 0;
  g_counting = true;
  Eigen::internal::set_is_malloc_allowed(false);
  try {
    for (int r = 0; r < 2; ++r) {
      f.factorize_values(lower);
      f.solve_in_place(x.data(), work);
    }
  } catch (const std::exception& e) {
    threw = true;
    std::printf("%s: %s\n", name.c_str(), e.what());
  }
  Eigen::internal::set_is_malloc_allowed(true);
  g_counting = false;
  if (threw || g_news != 0) std::printf("%s: allocated (eigen: %d, operator new: %ld)\n", name.c_str(), threw, g_news.load());
  CHECK(!threw);
  CHECK(g_news == 0);
  CHECK(f.info() == Eigen::Success);
}

}  // namespace

int main() {
  std::mt19937 gen(2024);

  // Tiny and structured.
  check_lower("n = 1", from_triplets(1, {{0, 0, 4.0}}));
  check_lower("n = 2", from_triplets(2, {{0, 0, 4.0}, {1, 0, 1.0}, {1, 1, 3.0}}));
  {
    Triplets t;
    for (int i = 0; i < 50; ++i) t.emplace_back(i, i, 1.0 + i);
    check_lower("diagonal", from_triplets(50, t));
  }
  check_lower("tridiagonal chain, n = 1000", tridiagonal(1000));
  check_lower("2-D Laplacian 30 x 30", grid_matrix(30, 30, 1, true, 1, gen));
  check_lower("2-D 9-point, 2 DOFs a node, 20 x 20", grid_matrix(20, 20, 1, false, 2, gen));
  check_lower("3-D Laplacian 12^3", grid_matrix(12, 12, 12, true, 1, gen));
  check_lower("3-D 27-point 3 DOFs a node 6^3", grid_matrix(6, 6, 6, false, 3, gen));
  check_lower("random SPD, n = 400", random_spd(400, 0.01, gen));
  check_lower("random SPD, dense-ish n = 150", random_spd(150, 0.3, gen));
  // A 3-D elastic solid: K + 1e4 M of trilinear bricks (the iteration matrix of an implicit scheme).
  // Its condition number is about 1e5, hence the looser comparison of factors.
  const SparseMatrix solid = elastic_block(5, 4, 4, 1e4);
  check_lower("hexahedral solid 5 x 4 x 4, K + 1e4 M", solid, true, 1e-11);
  check_lower("hexahedral solid 8 x 8 x 6, K + 1e6 M", elastic_block(8, 8, 6, 1e6), true, 1e-11);

  // Each ordering forced: nested dissection (multilevel bisection, compressed graph) and AMD, on
  // matrices with and without nodes of several DOFs, with no edges, and with several components.
  {
    using O = nvib::SupernodalOrdering;
    for (O o : {O::nested_dissection, O::amd}) {
      const std::string tag = o == O::amd ? " (AMD)" : " (nested dissection)";
      check_lower("n = 1" + tag, from_triplets(1, {{0, 0, 4.0}}), true, 1e-12, o);
      check_lower("n = 2" + tag, from_triplets(2, {{0, 0, 4.0}, {1, 0, 1.0}, {1, 1, 3.0}}), true, 1e-12, o);
      Triplets t;
      for (int i = 0; i < 500; ++i) t.emplace_back(i, i, 1.0 + i);
      check_lower("diagonal 500" + tag, from_triplets(500, t), true, 1e-12, o);
      check_lower("tridiagonal 3000" + tag, tridiagonal(3000), true, 1e-12, o);
      check_lower("2-D Laplacian 40 x 40" + tag, grid_matrix(40, 40, 1, true, 1, gen), true, 1e-12, o);
      check_lower("3-D 27-point 3 DOFs a node 8^3" + tag, grid_matrix(8, 8, 8, false, 3, gen), true, 1e-12, o);
      check_lower("random SPD, n = 600" + tag, random_spd(600, 0.005, gen), true, 1e-12, o);
      check_lower("hexahedral solid 7 x 6 x 5" + tag, elastic_block(7, 6, 5, 1e4), true, 1e-11, o);
      // Two components: a 2-D grid and a 3-D one, side by side.
      const SparseMatrix a = grid_matrix(20, 20, 1, true, 2, gen), b = grid_matrix(7, 7, 7, true, 1, gen);
      Triplets u;
      for (Index j = 0; j < a.outerSize(); ++j)
        for (SparseMatrix::InnerIterator it(a, j); it; ++it) u.emplace_back(static_cast<int>(it.row()), static_cast<int>(j), it.value());
      for (Index j = 0; j < b.outerSize(); ++j)
        for (SparseMatrix::InnerIterator it(b, j); it; ++it)
          u.emplace_back(static_cast<int>(it.row() + a.rows()), static_cast<int>(j + a.rows()), it.value());
      check_lower("two components" + tag, from_triplets(a.rows() + b.rows(), u), true, 1e-12, o);
    }
    // On a 3-D solid nested dissection needs fewer flops than AMD, and the automatic choice takes it.
    const SparseMatrix solid3 = elastic_block(10, 10, 8, 1e4);
    nvib::SupernodalCholesky<false> fa, fn, fx;
    fa.ordering = O::amd;
    fn.ordering = O::nested_dissection;
    fa.analyze(solid3);
    fn.analyze(solid3);
    fx.analyze(solid3);
    std::printf("3-D solid 10 x 10 x 8 (%ld DOFs): flops AMD %.3g, nested dissection %.3g, automatic %.3g\n",
                static_cast<long>(solid3.rows()), fa.simplicial_flops(), fn.simplicial_flops(), fx.simplicial_flops());
    CHECK(fn.simplicial_flops() < 0.75 * fa.simplicial_flops());
    CHECK(fx.simplicial_flops() == fn.simplicial_flops());
    // The automatic choice keeps nested dissection exactly where it saves a fifth of AMD's flops and a
    // twentieth of its entries: a 3-D solid, a thin slab (a 2-D mesh), a long bar.
    using F = nvib::SupernodalCholesky<false>;
    int took_nd = 0, took_amd = 0;
    for (const auto& [name, A] : {std::make_pair("solid 10 x 10 x 8", solid3),
                                  std::make_pair("slab 40 x 40 x 1", elastic_block(40, 40, 1, 1e4)),
                                  std::make_pair("bar 3 x 3 x 60", elastic_block(3, 3, 60, 1e4))}) {
      F a, d, x;
      a.ordering = O::amd;
      d.ordering = O::nested_dissection;
      a.analyze(A), d.analyze(A), x.analyze(A);
      const bool nd = d.simplicial_flops() <= F::kNestedDissectionFlops * a.simplicial_flops() &&
                      double(d.simplicial_nonzeros()) <= F::kNestedDissectionEntries * double(a.simplicial_nonzeros());
      const bool tried = a.simplicial_flops() >= 32.0 * double(a.simplicial_nonzeros());
      const F& expected = nd && tried ? d : a;
      std::printf("  %s: AMD flops %.3g entries %lld, nested dissection %.3g / %lld: automatic takes %s\n", name,
                  a.simplicial_flops(), (long long)a.simplicial_nonzeros(), d.simplicial_flops(),
                  (long long)d.simplicial_nonzeros(), nd && tried ? "nested dissection" : "AMD");
      CHECK(x.simplicial_flops() == expected.simplicial_flops() && x.simplicial_nonzeros() == expected.simplicial_nonzeros());
      (nd && tried ? took_nd : took_amd) += 1;
    }
    CHECK(took_nd >= 1);
    // On a chain AMD is kept (nested dissection is not even tried).
    nvib::SupernodalCholesky<false> fc;
    fc.analyze(tridiagonal(2000));
    CHECK(fc.simplicial_nonzeros() == 2 * 2000 - 1);
  }

  // Entries of the upper triangle stored (with other values): ignored.
  {
    const SparseMatrix lower = grid_matrix(9, 7, 1, false, 2, gen);
    SparseMatrix stored = symmetric_of(lower);
    for (Index j = 0; j < stored.outerSize(); ++j)
      for (SparseMatrix::InnerIterator it(stored, j); it; ++it)
        if (it.row() < j) it.valueRef() = 1e6 * (1.0 + static_cast<double>(it.row()));  // garbage above
    check_matrix("upper triangle stored and ignored", stored, symmetric_of(lower), true);
  }

  // Refactorisation: new values on the same pattern, the analysis kept.
  {
    const SparseMatrix a1 = elastic_block(4, 4, 3, 1e4), a2 = elastic_block(4, 4, 3, 3e7);
    for (bool ldlt : {false, true}) {
      auto run = [&](auto& f) {
        f.analyze(a1);
        Vector b = Vector::LinSpaced(a1.rows(), -1.0, 2.0), x = b, work(a1.rows());
        f.factorize_values(a1);
        f.solve_in_place(x.data(), work);
        CHECK(residual(symmetric_of(a1), x, b) <= 1e-12);
        f.factorize_values(a2);
        CHECK(f.info() == Eigen::Success);
        x = b;
        f.solve_in_place(x.data(), work);
        CHECK(residual(symmetric_of(a2), x, b) <= 1e-12);
      };
      if (ldlt) {
        nvib::SupernodalCholesky<true> f;
        run(f);
      } else {
        nvib::SupernodalCholesky<false> f;
        run(f);
      }
    }
  }

  // The ordering kept for the next matrix of the same pattern (a batch's runs on one model): taken from
  // the cache, it gives the same permutation and the same factors, bit for bit; another pattern, another
  // requested ordering or a small matrix is analysed afresh.
  {
    using O = nvib::SupernodalOrdering;
    using F = nvib::SupernodalCholesky<true>;
    // A pattern of this test alone: a 3-D solid with one extra coupling far off the diagonal.
    SparseMatrix base = elastic_block(9, 8, 7, 1e4);
    SparseMatrix extra(base.rows(), base.cols());
    extra.insert(base.rows() - 1, 0) = 1e-3;
    const SparseMatrix a1 = SparseMatrix(base + extra);
    const SparseMatrix a2 = SparseMatrix(elastic_block(9, 8, 7, 3e6) + extra);  // same pattern, other values
    CHECK(a1.rows() >= F::kOrderingCacheFrom);
    F f1, f2, f3, fo;
    f1.analyze(a1);
    CHECK(!f1.ordering_reused());
    f2.analyze(a2);
    CHECK(f2.ordering_reused());
    CHECK(f2.permutation() == f1.permutation() && f2.ordering_used() == f1.ordering_used());
    CHECK(f2.nonzeros() == f1.nonzeros() && f2.flops() == f1.flops() && f2.supernodes() == f1.supernodes());
    f3.analyze(a2);  // a2 again, analysed from the kept ordering: the factors of a fresh analysis, bit for bit
    f1.analyze(a2);
    f1.factorize_values(a2);
    f3.factorize_values(a2);
    CHECK(f1.info() == Eigen::Success && f3.info() == Eigen::Success);
    CHECK(f1.pivots() == f3.pivots());
    Vector b = Vector::LinSpaced(a2.rows(), -1.0, 2.0), x1 = b, x3 = b, work(a2.rows());
    f1.solve_in_place(x1.data(), work);
    f3.solve_in_place(x3.data(), work);
    CHECK(x1 == x3);
    CHECK(residual(symmetric_of(a2), x3, b) <= 1e-10);
    fo.ordering = O::amd;  // another requested ordering: its own entry
    fo.analyze(a1);
    CHECK(!fo.ordering_reused());
    const SparseMatrix other = elastic_block(9, 8, 6, 1e4);  // another pattern
    F g;
    g.analyze(other);
    CHECK(!g.ordering_reused());
    const SparseMatrix small = grid_matrix(20, 20, 1, true, 1, gen);  // 400 rows: not kept
    F s1, s2;
    s1.analyze(small);
    s2.analyze(small);
    CHECK(!s2.ordering_reused());
    // Threads analysing one pattern at once: each gets a correct analysis, and the cache one entry.
    std::vector<std::thread> threads;
    std::vector<F> fs(4);
    const SparseMatrix a3 = elastic_block(9, 9, 7, 1e4);
    for (auto& f : fs) threads.emplace_back([&f, &a3] { f.analyze(a3); });
    for (auto& t : threads) t.join();
    for (auto& f : fs) CHECK(f.permutation() == fs[0].permutation());
    F after;
    after.analyze(a3);
    CHECK(after.ordering_reused());
  }

  // Indefinite (no zero pivot): LL^T reports it, LDL^T solves it, with the inertia of Eigen's LDL^T.
  {
    const SparseMatrix lower = grid_matrix(12, 12, 1, true, 1, gen, 2.7);  // shifted into the spectrum
    check_lower("indefinite 2-D (shifted Laplacian)", lower, false, 1e-10);
    nvib::SupernodalCholesky<true> f;
    f.analyze(lower);
    f.factorize_values(lower);
    CHECK(f.info() == Eigen::Success);
    Eigen::SimplicialLDLT<SparseMatrix, Eigen::Lower> ref(symmetric_of(lower));
    const Index neg = (f.pivots().array() < 0).count(), neg_ref = (ref.vectorD().array() < 0).count();
    CHECK(neg == neg_ref);
    CHECK(neg > 0);
    // A saddle point: [K B^T; B 0] with a zero diagonal block, ordered so that no pivot is zero.
    check_lower("indefinite 2 x 2 [1 2; 2 1]", from_triplets(2, {{0, 0, 1.0}, {1, 0, 2.0}, {1, 1, 1.0}}), false);
  }

  // Singular: a zero pivot is reported by both, never a silent NaN.
  {
    auto singular = [&](const std::string& name, const SparseMatrix& lower) {
      nvib::SupernodalCholesky<false> f;
      nvib::SupernodalCholesky<true> g;
      f.analyze(lower);
      f.factorize_values(lower);
      g.analyze(lower);
      g.factorize_values(lower);
      if (f.info() != Eigen::NumericalIssue || g.info() != Eigen::NumericalIssue) std::printf("%s: not reported\n", name.c_str());
      CHECK(f.info() == Eigen::NumericalIssue);
      CHECK(g.info() == Eigen::NumericalIssue);
    };
    // The path graph's Laplacian (free ends): integer pivots, the last exactly zero.
    {
      Triplets t;
      const int n = 200;
      for (int i = 0; i < n; ++i) {
        t.emplace_back(i, i, (i == 0 || i == n - 1) ? 1.0 : 2.0);
        if (i > 0) t.emplace_back(i, i - 1, -1.0);
      }
      singular("path Laplacian", from_triplets(n, t));
    }
    singular("[1 1; 1 1]", from_triplets(2, {{0, 0, 1.0}, {1, 0, 1.0}, {1, 1, 1.0}}));
    singular("[0 1; 1 0]", from_triplets(2, {{0, 0, 0.0}, {1, 0, 1.0}, {1, 1, 0.0}}));
    {
      SparseMatrix a = grid_matrix(6, 6, 6, false, 3, gen);  // a zero row and column in a large supernode
      for (Index j = 0; j < a.outerSize(); ++j)
        for (SparseMatrix::InnerIterator it(a, j); it; ++it)
          if (it.row() == 300 || j == 300) it.valueRef() = 0.0;
      singular("zero row in a 3-D matrix", a);
    }
    {
      SparseMatrix a = grid_matrix(10, 10, 10, true, 1, gen);  // a NaN
      a.coeffRef(500, 500) = std::numeric_limits<double>::quiet_NaN();
      singular("NaN on the diagonal", a);
    }
  }

  // No heap allocation after analyze(): small supernodes, and large ones whose products and
  // triangular solves go through Eigen's blocked kernels (the 3-D Laplacian's top separator has 256
  // columns, over Eigen's stack-buffer block).
  {
    const SparseMatrix lap = grid_matrix(16, 16, 16, true, 1, gen);
    check_no_alloc<false>("no malloc, 3-D Laplacian 16^3, LLT", lap);
    check_no_alloc<true>("no malloc, 3-D Laplacian 16^3, LDLT", lap);
    check_no_alloc<false>("no malloc, chain, LLT", tridiagonal(5000));
    check_no_alloc<true>("no malloc, solid, LDLT", elastic_block(6, 6, 5, 1e4));
    check_lower("3-D Laplacian 16^3", lap);
  }
  return nvib_test::finish("test_supernodal");
}
