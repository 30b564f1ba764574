// out += K u + C v for the constant linear parts of a model, the product every explicit step and
// every residual makes. Four ways, chosen once when the model is built:
//   band      K and C each a complete band of half-width 0, 1 or 2 (every position of the band stored:
//             a chain, a shear building, a beam on springs): the band's entries row by row, the width
//             known at compile time, interior rows without range tests. On the six-storey building it
//             takes half the instructions of the general way. Where a run of rows has the same values
//             on each diagonal (uniform storeys or links: the dampers of a chain), those rows multiply
//             by the values held in registers and read no matrix: on a chain of 10^6 DOFs the product
//             read 24 bytes per DOF of C's diagonals, a third of the explicit step's memory traffic.
//   rayleigh  a lumped mass m and C = alpha diag(m) + beta K to round-off (Rayleigh damping as an
//             engineer assembles it, or mass- or stiffness-proportional damping): by rows,
//             K (u + beta v) + alpha m v. The product reads K's indices and values once where the
//             others read those of K and of C: half the memory traffic of a large model's step.
//             Where K's DOFs come in nodes of 3 (or 2) consecutive DOFs whose blocks K stores nearly
//             full (a 3-D solid's mesh), K is held by node blocks instead (node_block()).
//   shared    K and C stored on one pattern (a consistent mass's Rayleigh damping, any C assembled on
//             K's pattern): by rows, each column's K and C terms together, the indices read once; by
//             node blocks where K's are nearly full, as the rayleigh form.
//   rows      any pattern: the compressed rows of K, then those of C.
// The band and the rows add each row's terms in the order of a product by columns (K's, then C's,
// columns ascending): they agree bit for bit. The rayleigh and shared ways reorder the sums (and
// rayleigh rounds beta v and u + beta v): they agree with the rows to round-off, a few units in the last
// place of the products' magnitudes |K| |u| + |C| |v| (tests/cpp/test_sparse.cpp). They are taken for
// K and C of kReorderFrom stored entries or more (FE models, where the product is much of a step);
// smaller models keep the rows' sums bit for bit.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "../base/compiler.hpp"
#include "../base/types.hpp"

namespace nvib {

class LinearProduct {
 public:
  using RowMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor, int>;

  LinearProduct() = default;
  // K, C: square, compressed; an empty one (no stored entry) takes no part. lumped_mass: the diagonal
  // of a lumped mass (nullptr for another mass), against which C is tried for Rayleigh damping.
  LinearProduct(const SparseMatrix& K, const SparseMatrix& C, const Vector* lumped_mass = nullptr)
      : n_(std::max(K.rows(), C.rows())) {
    K_ = K;
    C_ = C;
    K_.makeCompressed();
    C_.makeCompressed();
    reach_ = std::max(reach_of(K_), reach_of(C_));
    const int bk = band_of(K_, n_), bc = band_of(C_, n_);
    if (bk >= kNone && bc >= kNone && !(bk == kNone && bc == kNone)) {
      kb_ = band_values(K_, bk, n_);
      cb_ = band_values(C_, bc, n_);
      find_constant_rows(bk, bc);
      kernel_ = pick(bk, bc);
      form_ = Form::band;
      K_ = RowMatrix();  // the band holds every entry
      C_ = RowMatrix();
    } else if (bk == kNone && bc == kNone) {
      kernel_ = &add_rows;  // nothing to add
      form_ = Form::none;
    } else if (K_.nonZeros() + C_.nonZeros() < kReorderFrom) {
      kernel_ = &add_rows;  // a small product: the rows' sums, as they always were
      form_ = Form::rows;
    } else if (lumped_mass && lumped_mass->size() == n_ && rayleigh_of(K_, C_, *lumped_mass, alpha_, beta_)) {
      alpha_m_ = alpha_ * *lumped_mass;
      kernel_ = &add_rayleigh;
      form_ = Form::rayleigh;
      C_ = RowMatrix();  // C = alpha M + beta K: K and alpha m hold it
      formed_ = &add_rayleigh_formed;
      if (node_blocks<3>(false))
        kernel_ = &add_rayleigh_blocks<3>, formed_ = &add_rayleigh_blocks_formed<3>;
      else if (node_blocks<2>(false))
        kernel_ = &add_rayleigh_blocks<2>, formed_ = &add_rayleigh_blocks_formed<2>;
    } else if (same_pattern(K_, C_)) {
      kernel_ = &add_shared;
      form_ = Form::shared;
      if (node_blocks<3>(true))
        kernel_ = &add_shared_blocks<3>;
      else if (node_blocks<2>(true))
        kernel_ = &add_shared_blocks<2>;
    } else {
      kernel_ = &add_rows;
      form_ = Form::rows;
    }
  }

  // out += K u + C v (arrays of n doubles; out apart from u and v).
  void add(const double* u, const double* v, double* out) const { kernel_(*this, u, v, out, 0, n_); }
  // The same, with n doubles of the caller's as scratch (apart from u, v and out): the rayleigh form
  // forms u + beta v there once, each entry rounded as the rows would round it at every one of its
  // column's entries (a 3-D solid's column has about 80), then takes the rows on it: one gather and one
  // multiply-add an entry instead of two gathers and two of each. The same bits as add().
  void add(const double* u, const double* v, double* out, double* scratch) const {
    if (uses_scratch() && scratch != nullptr)
      formed_(*this, u, v, out, scratch);
    else
      kernel_(*this, u, v, out, 0, n_);
  }
  // add() with a scratch uses it (its size: n).
  bool uses_scratch() const { return formed_ != nullptr; }
  // The same for rows r0 .. r1 - 1 only (they read u and v within reach() of the rows).
  void add(const double* u, const double* v, double* out, Index r0, Index r1) const { kernel_(*this, u, v, out, r0, r1); }
  // K and C holding fewer stored entries than this together keep the rows' sums (rayleigh and shared
  // reorder them): in a small model the product is a small part of a step, and its trajectories stay
  // bit for bit those of the rows.
  static constexpr Index kReorderFrom = 4096;

  enum class Form { none, band, rayleigh, shared, rows };
  // Which way the product is taken (see the top of this file), and its name.
  Form form() const { return form_; }
  const char* form_name() const {
    switch (form_) {
      case Form::band: return "band";
      case Form::rayleigh: return "rayleigh";
      case Form::shared: return "shared";
      case Form::none: return "none";
      default: return "rows";
    }
  }
  // The band form is used.
  bool banded() const { return form_ == Form::band; }
  // The band's rows whose diagonals hold the same values (uniform storeys, links of one kind): the band
  // product multiplies them by constants held in registers instead of reading the diagonals, the same
  // products in the same order. Empty (first == second) where there are fewer than kConstantRows.
  std::pair<Index, Index> constant_rows() const { return {const_lo_, const_hi_}; }
  static constexpr Index kConstantRows = 64;
  // The coefficients of C = alpha M + beta K where form() is rayleigh (else 0).
  double rayleigh_alpha() const { return alpha_; }
  double rayleigh_beta() const { return beta_; }
  // How far from its row a row's entries lie: max |i - j| over the stored entries of K and C.
  Index reach() const { return reach_; }
  // The rayleigh and shared forms' node blocks: B = 3 or 2 where K (and C) are held by B x B blocks,
  // else 0.
  //   DOFs B k .. B k + B - 1 form node k (n a multiple of B); K is stored by the blocks of two nodes
  //   that hold some entry, each block row's blocks by column, a block's B^2 values row by row, and a
  //   position K does not store held as -0.0. A block row reads its blocks' values with no index of
  //   their own and each block's B entries of u + beta v once: 1 + B + B^2 loads for B^2 entries where
  //   the rows make 3 an entry. Measured on the 8-node brick meshes of benchmarks/fe_models.py (3 DOFs a
  //   node, blocks 1.14 times K's entries): the product 1.36 times as fast as the rows.
  //   Each row adds the same terms in the same order as the rows (columns ascending); a held -0.0 adds
  //   -0.0 x, which leaves a sum as it was, except that an exact -0 sum becomes +0 where x < 0: the same
  //   values, the sign of a zero aside. Taken where the blocks hold at most kMaxPadding times K's
  //   entries (2-D quadrilateral walls, 1.38, keep the rows).
  int node_block() const { return block_; }
  static constexpr double kMaxPadding = 1.25;

 private:
  using Kernel = void (*)(const LinearProduct&, const double*, const double*, double*, Index, Index);
  // Every row with u + beta v formed in a scratch (the rayleigh form's add() with a scratch).
  using Formed = void (*)(const LinearProduct&, const double*, const double*, double*, double*);
  static constexpr int kNone = -1;     // no matrix
  static constexpr int kGeneral = -2;  // not a complete band of half-width <= 2
  static constexpr int kMaxBand = 2;

  static Index reach_of(const RowMatrix& A) {
    Index r = 0;
    for (Index i = 0; i < A.outerSize(); ++i)
      for (RowMatrix::InnerIterator it(A, i); it; ++it) r = std::max<Index>(r, std::abs(it.col() - i));
    return r;
  }
  // K and C store the same positions (and both store some).
  static bool same_pattern(const RowMatrix& K, const RowMatrix& C) {
    if (K.nonZeros() == 0 || K.nonZeros() != C.nonZeros() || K.outerSize() != C.outerSize()) return false;
    return std::equal(K.outerIndexPtr(), K.outerIndexPtr() + K.outerSize() + 1, C.outerIndexPtr()) &&
           std::equal(K.innerIndexPtr(), K.innerIndexPtr() + K.nonZeros(), C.innerIndexPtr());
  }
  // Whether C = alpha diag(m) + beta K to round-off, and alpha and beta. beta is C_ij / K_ij at the
  // largest off-diagonal |K_ij|; alpha is (C_ii - beta K_ii) / m_i at the diagonal position where that
  // difference cancels least. Then every position stored in K or C or on the diagonal must satisfy
  //   |C_ij - (alpha m_i [i = j] + beta K_ij)| <= 64 eps (|alpha m_i [i = j]| + |beta K_ij|),
  // a few roundings of C's own assembly and of the two coefficients: a C that is not of this form
  // (a damper between two DOFs, a modal damping matrix) misses it by far more.
  static bool rayleigh_of(const RowMatrix& K, const RowMatrix& C, const Vector& m, double& alpha, double& beta) {
    alpha = beta = 0.0;
    const Index n = K.outerSize();
    if (K.nonZeros() == 0 || C.nonZeros() == 0 || C.outerSize() != n || m.size() != n) return false;
    const int *ko = K.outerIndexPtr(), *ki = K.innerIndexPtr(), *co = C.outerIndexPtr(), *ci = C.innerIndexPtr();
    const double *kv = K.valuePtr(), *cv = C.valuePtr();
    // f(i, j, K_ij, C_ij) over the union of K's and C's positions and the diagonal, by rows
    auto for_each_position = [&](auto&& f) {
      for (Index i = 0; i < n; ++i) {
        int p = ko[i], pe = ko[i + 1], q = co[i], qe = co[i + 1];
        bool diagonal = false;
        while (p < pe || q < qe) {
          const int j = (q >= qe || (p < pe && ki[p] <= ci[q])) ? ki[p] : ci[q];
          const double kij = (p < pe && ki[p] == j) ? kv[p++] : 0.0;
          const double cij = (q < qe && ci[q] == j) ? cv[q++] : 0.0;
          diagonal = diagonal || j == i;
          if (!f(i, Index(j), kij, cij)) return false;
        }
        if (!diagonal && !f(i, i, 0.0, 0.0)) return false;
      }
      return true;
    };
    double kbig = 0.0;
    for_each_position([&](Index i, Index j, double kij, double cij) {
      if (i != j && std::abs(kij) > kbig) kbig = std::abs(kij), beta = cij / kij;
      return true;
    });
    if (kbig == 0.0) return false;  // K diagonal: nothing tells beta from alpha
    double least_cancelled = -1.0;
    for_each_position([&](Index i, Index j, double kij, double cij) {
      if (i != j) return true;
      const double r = cij - beta * kij, size = std::abs(cij) + std::abs(beta * kij);
      const double share = size > 0.0 ? std::abs(r) / size : 0.0;
      if (share > least_cancelled && m[i] > 0.0) least_cancelled = share, alpha = r / m[i];
      return true;
    });
    if (!std::isfinite(alpha) || !std::isfinite(beta)) return false;
    const double tol = 64.0 * std::numeric_limits<double>::epsilon();
    return for_each_position([&](Index i, Index j, double kij, double cij) {
      const double am = i == j ? alpha * m[i] : 0.0, bk = beta * kij;
      return std::abs(cij - (am + bk)) <= tol * (std::abs(am) + std::abs(bk));
    });
  }
  // The half-width B of A's band if every position of it is stored (rows i, columns max(0, i - B) ..
  // min(n - 1, i + B), nothing else): -1 if A stores nothing, -2 if A is not such a band.
  static int band_of(const RowMatrix& A, Index n) {
    if (A.nonZeros() == 0) return kNone;
    int B = 0;
    for (Index i = 0; i < A.outerSize(); ++i)
      for (RowMatrix::InnerIterator it(A, i); it; ++it) B = std::max<int>(B, static_cast<int>(std::abs(it.col() - i)));
    if (B > kMaxBand) return kGeneral;
    for (Index i = 0; i < n; ++i) {
      const Index lo = std::max<Index>(0, i - B), hi = std::min<Index>(n - 1, i + B);
      const Index stored = A.outerIndexPtr()[i + 1] - A.outerIndexPtr()[i];
      if (stored != hi - lo + 1) return kGeneral;  // (columns are unique and inside the band: all of it)
    }
    return B;
  }
  // The band by diagonals: A(i, i + o) at (o + B) n + i, o = -B .. B; positions outside the matrix
  // stay 0 and are never read. Consecutive rows read consecutive entries of each diagonal and of x.
  static std::vector<double> band_values(const RowMatrix& A, int B, Index n) {
    if (B < 0) return {};
    std::vector<double> b(static_cast<std::size_t>(n * (2 * B + 1)), 0.0);
    for (Index i = 0; i < A.outerSize(); ++i)
      for (RowMatrix::InnerIterator it(A, i); it; ++it) b[static_cast<std::size_t>((it.col() - i + B) * n + i)] = it.value();
    return b;
  }

  // The longest run of interior rows (every column of the band inside the matrix) around the middle row
  // whose diagonals of K and of C hold, each, one value bit for bit: const_lo_ .. const_hi_ - 1, and
  // those values in kc_ and cc_.
  void find_constant_rows(int bk, int bc) {
    const Index B = std::max({bk, bc, 0}), lo = B, hi = n_ - B;
    const_lo_ = const_hi_ = 0;
    if (hi - lo < kConstantRows) return;
    const Index mid = lo + (hi - lo) / 2;
    auto same = [&](const std::vector<double>& b, int w, Index i) {
      for (int o = -w; o <= w; ++o) {
        const double x = b[static_cast<std::size_t>((o + w) * n_ + i)], y = b[static_cast<std::size_t>((o + w) * n_ + mid)];
        if (std::memcmp(&x, &y, sizeof x) != 0) return false;
      }
      return true;
    };
    auto row_same = [&](Index i) { return (bk < 0 || same(kb_, bk, i)) && (bc < 0 || same(cb_, bc, i)); };
    Index a = mid, z = mid + 1;
    while (a > lo && row_same(a - 1)) --a;
    while (z < hi && row_same(z)) ++z;
    if (z - a < kConstantRows) return;
    const_lo_ = a;
    const_hi_ = z;
    for (int o = -bk; o <= bk; ++o) kc_[o + bk] = kb_[static_cast<std::size_t>((o + bk) * n_ + mid)];
    for (int o = -bc; o <= bc; ++o) cc_[o + bc] = cb_[static_cast<std::size_t>((o + bc) * n_ + mid)];
  }

  // Row i of a band of half-width B (B < 0: none): s += A(i, j) x(j) for the columns j of the band,
  // ascending, skipping those outside 0 .. n - 1 (the first and last B rows).
  template <int B>
  static inline double band_row_checked(double s, const double* a, const double* x, Index i, Index n) {
    if constexpr (B >= 0) {
      for (int o = -B; o <= B; ++o) {
        const Index j = i + o;
        if (j >= 0 && j < n) s += a[(o + B) * n + i] * x[j];
      }
    }
    (void)a, (void)x, (void)i, (void)n;
    return s;
  }
  template <int BK, int BC>
  static void add_band(const LinearProduct& p, const double* __restrict u, const double* __restrict v,
                       double* __restrict out, Index r0, Index r1) {
    constexpr int B = BK > BC ? (BK > 0 ? BK : 0) : (BC > 0 ? BC : 0);
    const Index n = p.n_;
    const double* __restrict kb = p.kb_.data();
    const double* __restrict cb = p.cb_.data();
    const Index head = std::min<Index>(std::max<Index>(B, r0), r1), tail = std::max<Index>(head, std::min<Index>(n - B, r1));
    for (Index i = r0; i < head; ++i)
      out[i] = band_row_checked<BC>(band_row_checked<BK>(out[i], kb, u, i, n), cb, v, i, n);
    // The interior rows: every column of the band inside the matrix, the widths known here; where the
    // diagonals are constant, their values from registers.
    auto interior = [&](Index i0, Index i1) {
      for (Index i = i0; i < i1; ++i) {
        double s = out[i];
        if constexpr (BK >= 0)
          for (int o = -BK; o <= BK; ++o) s += kb[(o + BK) * n + i] * u[i + o];
        if constexpr (BC >= 0)
          for (int o = -BC; o <= BC; ++o) s += cb[(o + BC) * n + i] * v[i + o];
        out[i] = s;
      }
    };
    const Index c0 = std::min(std::max(p.const_lo_, head), tail), c1 = std::max(std::min(p.const_hi_, tail), c0);
    interior(head, c0);
    if (c1 > c0) {
      constexpr int WK = BK >= 0 ? 2 * BK + 1 : 1, WC = BC >= 0 ? 2 * BC + 1 : 1;
      double kc[WK], cc[WC];
      for (int q = 0; q < WK; ++q) kc[q] = p.kc_[q];
      for (int q = 0; q < WC; ++q) cc[q] = p.cc_[q];
      for (Index i = c0; i < c1; ++i) {
        double s = out[i];
        if constexpr (BK >= 0)
          for (int o = -BK; o <= BK; ++o) s += kc[o + BK] * u[i + o];
        if constexpr (BC >= 0)
          for (int o = -BC; o <= BC; ++o) s += cc[o + BC] * v[i + o];
        out[i] = s;
      }
    }
    interior(c1, tail);
    for (Index i = tail; i < r1; ++i)
      out[i] = band_row_checked<BC>(band_row_checked<BK>(out[i], kb, u, i, n), cb, v, i, n);
    (void)kb, (void)cb, (void)u, (void)v;
  }
  // out_i = finish(i, out_i + sum_q term(q)) for rows r0 .. r1 - 1, q = o[i] .. o[i+1] - 1 in order (the
  // rayleigh form's rows). Four rows at a time: each row's sum is a chain of additions (each waits on the
  // one before), and four rows' chains side by side keep the adder busy where one row's alone waited on
  // it (three loads an entry: the load ports still have room). Every row adds the same terms in the same
  // order as row by row: the same bits.
  template <class Term, class Finish>
  static NVIB_ALWAYS_INLINE void by_rows(const int* __restrict o, double* __restrict out, Index r0, Index r1, Term term,
                                         Finish finish) {
    Index i = r0;
    for (; i + 4 <= r1; i += 4) {
      const int q0 = o[i], q1 = o[i + 1], q2 = o[i + 2], q3 = o[i + 3], e = o[i + 4];
      const int l0 = q1 - q0, l1 = q2 - q1, l2 = q3 - q2, l3 = e - q3;
      const int m = std::min(std::min(l0, l1), std::min(l2, l3));
      double s0 = out[i], s1 = out[i + 1], s2 = out[i + 2], s3 = out[i + 3];
      for (int k = 0; k < m; ++k) {
        s0 += term(q0 + k);
        s1 += term(q1 + k);
        s2 += term(q2 + k);
        s3 += term(q3 + k);
      }
      for (int k = m; k < l0; ++k) s0 += term(q0 + k);
      for (int k = m; k < l1; ++k) s1 += term(q1 + k);
      for (int k = m; k < l2; ++k) s2 += term(q2 + k);
      for (int k = m; k < l3; ++k) s3 += term(q3 + k);
      out[i] = finish(i, s0);
      out[i + 1] = finish(i + 1, s1);
      out[i + 2] = finish(i + 2, s2);
      out[i + 3] = finish(i + 3, s3);
    }
    for (; i < r1; ++i) {
      double s = out[i];
      for (int q = o[i], e = o[i + 1]; q < e; ++q) s += term(q);
      out[i] = finish(i, s);
    }
  }
  static void add_rows(const LinearProduct& p, const double* __restrict u, const double* __restrict v,
                       double* __restrict out, Index r0, Index r1) {
    const RowMatrix &K = p.K_, &C = p.C_;
    const int *ko = K.outerIndexPtr(), *ki = K.innerIndexPtr(), *co = C.outerIndexPtr(), *ci = C.innerIndexPtr();
    const double *kv = K.valuePtr(), *cv = C.valuePtr();
    const bool k = K.nonZeros() > 0, c = C.nonZeros() > 0;
    for (Index i = r0; i < r1; ++i) {
      double s = out[i];
      if (k)
        for (int q = ko[i], e = ko[i + 1]; q < e; ++q) s += kv[q] * u[ki[q]];
      if (c)
        for (int q = co[i], e = co[i + 1]; q < e; ++q) s += cv[q] * v[ci[q]];
      out[i] = s;
    }
  }
  // C = alpha diag(m) + beta K: row i is sum_j K_ij (u_j + beta v_j) + alpha m_i v_i.
  static void add_rayleigh(const LinearProduct& p, const double* __restrict u, const double* __restrict v,
                           double* __restrict out, Index r0, Index r1) {
    const int *ko = p.K_.outerIndexPtr(), *ki = p.K_.innerIndexPtr();
    const double* __restrict kv = p.K_.valuePtr();
    const double* __restrict am = p.alpha_m_.data();
    const double beta = p.beta_;
    by_rows(
        ko, out, r0, r1,
        [=](int q) {
          const int j = ki[q];
          return kv[q] * (u[j] + beta * v[j]);
        },
        [=](Index i, double s) { return s + am[i] * v[i]; });
  }
  // add_rayleigh on every row, u + beta v formed once in w.
  static void add_rayleigh_formed(const LinearProduct& p, const double* __restrict u, const double* __restrict v,
                                  double* __restrict out, double* __restrict w) {
    const Index n = p.n_;
    const double beta = p.beta_;
    for (Index j = 0; j < n; ++j) w[j] = u[j] + beta * v[j];
    const int *ko = p.K_.outerIndexPtr(), *ki = p.K_.innerIndexPtr();
    const double* __restrict kv = p.K_.valuePtr();
    const double* __restrict am = p.alpha_m_.data();
    const double* wc = w;
    by_rows(
        ko, out, 0, n, [=](int q) { return kv[q] * wc[ki[q]]; }, [=](Index i, double s) { return s + am[i] * v[i]; });
  }
  // K by node blocks of B DOFs (node_block()), if n is a multiple of B and the blocks hold at most
  // kMaxPadding times K's stored entries; K's rows must hold their columns ascending (compressed).
  // with_c: C too, on the same blocks (the shared form: C on K's pattern). Once blocked, the compressed
  // rows are released: the blocks hold every entry.
  template <int B>
  bool node_blocks(bool with_c) {
    if (n_ % B != 0 || K_.nonZeros() == 0) return false;
    const Index nb = n_ / B;
    const int *ko = K_.outerIndexPtr(), *ki = K_.innerIndexPtr();
    const double* kv = K_.valuePtr();
    const double limit = kMaxPadding * static_cast<double>(K_.nonZeros());
    std::vector<int> bo(static_cast<std::size_t>(nb) + 1, 0), bi, where(static_cast<std::size_t>(nb), -1);
    for (Index I = 0; I < nb; ++I) {
      const std::size_t start = bi.size();
      for (Index i = B * I; i < B * I + B; ++i)
        for (int q = ko[i]; q < ko[i + 1]; ++q) {
          const int J = ki[q] / B;
          if (where[static_cast<std::size_t>(J)] != static_cast<int>(I)) where[static_cast<std::size_t>(J)] = static_cast<int>(I), bi.push_back(J);
        }
      std::sort(bi.begin() + static_cast<std::ptrdiff_t>(start), bi.end());
      if (static_cast<double>(bi.size()) * B * B > limit || bi.size() > static_cast<std::size_t>(std::numeric_limits<int>::max()) / (B * B))
        return false;
      bo[static_cast<std::size_t>(I) + 1] = static_cast<int>(bi.size());
    }
    std::vector<double> bv(bi.size() * B * B, -0.0), cbv(with_c ? bi.size() * B * B : 0, -0.0);
    const double* cv = with_c ? C_.valuePtr() : nullptr;  // (on K's pattern: entry q of K is entry q of C)
    for (Index I = 0; I < nb; ++I) {
      for (int q = bo[static_cast<std::size_t>(I)]; q < bo[static_cast<std::size_t>(I) + 1]; ++q) where[static_cast<std::size_t>(bi[static_cast<std::size_t>(q)])] = q;
      for (Index i = B * I; i < B * I + B; ++i)
        for (int q = ko[i]; q < ko[i + 1]; ++q) {
          const int J = ki[q] / B, c = ki[q] - B * J, r = static_cast<int>(i - B * I);
          const std::size_t at = static_cast<std::size_t>(where[static_cast<std::size_t>(J)]) * B * B + static_cast<std::size_t>(r * B + c);
          bv[at] = kv[q];
          if (with_c) cbv[at] = cv[q];
        }
    }
    bo_ = std::move(bo);
    bi_ = std::move(bi);
    bv_ = std::move(bv);
    cbv_ = std::move(cbv);
    block_ = B;
    K_ = RowMatrix();
    C_ = RowMatrix();
    return true;
  }
  // add_rayleigh on node blocks, rows r0 .. r1 - 1 (any rows: each its block row's row r).
  template <int B>
  static void add_rayleigh_blocks(const LinearProduct& p, const double* __restrict u, const double* __restrict v,
                                  double* __restrict out, Index r0, Index r1) {
    const int *__restrict bo = p.bo_.data(), *__restrict bi = p.bi_.data();
    const double *__restrict bv = p.bv_.data(), *__restrict am = p.alpha_m_.data();
    const double beta = p.beta_;
    for (Index i = r0; i < r1; ++i) {
      const Index I = i / B, r = i - B * I;
      double s = out[i];
      for (int q = bo[I], e = bo[I + 1]; q < e; ++q) {
        const double* a = bv + static_cast<Index>(q) * (B * B) + r * B;
        const Index j = static_cast<Index>(bi[q]) * B;
        for (int c = 0; c < B; ++c) s += a[c] * (u[j + c] + beta * v[j + c]);
      }
      out[i] = s + am[i] * v[i];
    }
  }
  // The same on every row, u + beta v formed once in w (as add_rayleigh_formed), a block row's B sums
  // side by side.
  template <int B>
  static void add_rayleigh_blocks_formed(const LinearProduct& p, const double* __restrict u, const double* __restrict v,
                                         double* __restrict out, double* __restrict w) {
    const Index n = p.n_, nb = n / B;
    const double beta = p.beta_;
    for (Index j = 0; j < n; ++j) w[j] = u[j] + beta * v[j];
    const int *__restrict bo = p.bo_.data(), *__restrict bi = p.bi_.data();
    const double *__restrict bv = p.bv_.data(), *__restrict am = p.alpha_m_.data();
    const double* __restrict wc = w;
    for (Index I = 0; I < nb; ++I) {
      double* __restrict o = out + B * I;
      double s[B];
      for (int r = 0; r < B; ++r) s[r] = o[r];
      for (int q = bo[I], e = bo[I + 1]; q < e; ++q) {
        const double* a = bv + static_cast<Index>(q) * (B * B);
        const double* x = wc + static_cast<Index>(bi[q]) * B;
        for (int c = 0; c < B; ++c) {
          const double xc = x[c];
          for (int r = 0; r < B; ++r) s[r] += a[r * B + c] * xc;
        }
      }
      for (int r = 0; r < B; ++r) o[r] = s[r] + am[B * I + r] * v[B * I + r];
    }
  }
  // add_shared on node blocks (C's values on K's blocks): rows r0 .. r1 - 1, the whole block rows among
  // them with their B sums side by side, each block's B entries of u and of v read once.
  template <int B>
  static void add_shared_blocks(const LinearProduct& p, const double* __restrict u, const double* __restrict v,
                                double* __restrict out, Index r0, Index r1) {
    const int *__restrict bo = p.bo_.data(), *__restrict bi = p.bi_.data();
    const double *__restrict kv = p.bv_.data(), *__restrict cv = p.cbv_.data();
    auto row = [&](Index i) {  // row r of its block row
      const Index I = i / B, r = i - B * I;
      double s = out[i];
      for (int q = bo[I], e = bo[I + 1]; q < e; ++q) {
        const Index o = static_cast<Index>(q) * (B * B) + r * B, j = static_cast<Index>(bi[q]) * B;
        for (int c = 0; c < B; ++c) s += kv[o + c] * u[j + c] + cv[o + c] * v[j + c];
      }
      out[i] = s;
    };
    const Index I0 = (r0 + B - 1) / B, I1 = std::max(I0, r1 / B);  // the whole block rows I0 .. I1 - 1
    for (Index i = r0; i < std::min(r1, B * I0); ++i) row(i);
    for (Index I = I0; I < I1; ++I) {
      double s[B];
      for (int r = 0; r < B; ++r) s[r] = out[B * I + r];
      for (int q = bo[I], e = bo[I + 1]; q < e; ++q) {
        const double *a = kv + static_cast<Index>(q) * (B * B), *g = cv + static_cast<Index>(q) * (B * B);
        const Index j = static_cast<Index>(bi[q]) * B;
        for (int c = 0; c < B; ++c) {
          const double x = u[j + c], y = v[j + c];
          for (int r = 0; r < B; ++r) s[r] += a[r * B + c] * x + g[r * B + c] * y;
        }
      }
      for (int r = 0; r < B; ++r) out[B * I + r] = s[r];
    }
    for (Index i = std::max(B * I1, r0); i < r1; ++i) row(i);
  }
  // K and C on one pattern: each position's two terms together (row by row: five loads an entry keep
  // the load ports busy; four rows side by side, as by_rows() takes them, measured 6-11 % slower).
  static void add_shared(const LinearProduct& p, const double* __restrict u, const double* __restrict v,
                         double* __restrict out, Index r0, Index r1) {
    const int *ko = p.K_.outerIndexPtr(), *ki = p.K_.innerIndexPtr();
    const double *__restrict kv = p.K_.valuePtr(), *__restrict cv = p.C_.valuePtr();
    for (Index i = r0; i < r1; ++i) {
      double s = out[i];
      for (int q = ko[i], e = ko[i + 1]; q < e; ++q) {
        const int j = ki[q];
        s += kv[q] * u[j] + cv[q] * v[j];
      }
      out[i] = s;
    }
  }
  template <int BK>
  static Kernel pick_c(int bc) {
    switch (bc) {
      case 0: return &add_band<BK, 0>;
      case 1: return &add_band<BK, 1>;
      case 2: return &add_band<BK, 2>;
      default: return &add_band<BK, kNone>;
    }
  }
  static Kernel pick(int bk, int bc) {
    switch (bk) {
      case 0: return pick_c<0>(bc);
      case 1: return pick_c<1>(bc);
      case 2: return pick_c<2>(bc);
      default: return pick_c<kNone>(bc);
    }
  }

  Index n_ = 0, reach_ = 0;
  RowMatrix K_, C_;
  std::vector<double> kb_, cb_;
  Index const_lo_ = 0, const_hi_ = 0;  // constant_rows()
  double kc_[2 * kMaxBand + 1] = {}, cc_[2 * kMaxBand + 1] = {};
  Vector alpha_m_;  // alpha m (rayleigh)
  int block_ = 0;                    // node_block()
  std::vector<int> bo_, bi_;         // the blocks: block row I's are bo_[I] .. bo_[I + 1] - 1, of block columns bi_
  std::vector<double> bv_;           // their values, B^2 a block, row by row
  std::vector<double> cbv_;          // C's on the same blocks (the shared form)
  double alpha_ = 0.0, beta_ = 0.0;
  Kernel kernel_ = &add_rows;
  Formed formed_ = nullptr;  // the rayleigh form's (uses_scratch())
  Form form_ = Form::none;
};

}  // namespace nvib
