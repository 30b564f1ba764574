// out += K u + C v for the constant linear parts of a model, the product every explicit step and
// every residual makes. By rows: each row's terms are added in the order of a product by columns
// (K's, then C's, columns ascending), so that every way below gives the same sums, bit for bit.
//
// Two ways, chosen once when the model is built:
//   band  K and C each a complete band of half-width 0, 1 or 2 (every position of the band stored:
//         a chain, a shear building, a beam on springs): the band's entries row by row, the width
//         known at compile time, interior rows without range tests. On the six-storey building it
//         takes half the instructions of the general way.
//   rows  any pattern: the compressed rows of K and C.
#pragma once

#include <algorithm>
#include <vector>

#include "../base/types.hpp"

namespace nvib {

class LinearProduct {
 public:
  using RowMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor, int>;

  LinearProduct() = default;
  // K, C: square, compressed; an empty one (no stored entry) takes no part.
  LinearProduct(const SparseMatrix& K, const SparseMatrix& C) : n_(std::max(K.rows(), C.rows())) {
    K_ = K;
    C_ = C;
    K_.makeCompressed();
    C_.makeCompressed();
    reach_ = std::max(reach_of(K_), reach_of(C_));
    const int bk = band_of(K_, n_), bc = band_of(C_, n_);
    if (bk >= kNone && bc >= kNone && !(bk == kNone && bc == kNone)) {
      kb_ = band_values(K_, bk, n_);
      cb_ = band_values(C_, bc, n_);
      kernel_ = pick(bk, bc);
      banded_ = true;
      K_ = RowMatrix();  // the band holds every entry
      C_ = RowMatrix();
    } else {
      kernel_ = &add_rows;
    }
  }

  // out += K u + C v (arrays of n doubles; out apart from u and v).
  void add(const double* u, const double* v, double* out) const { kernel_(*this, u, v, out, 0, n_); }
  // The same for rows r0 .. r1 - 1 only (they read u and v within reach() of the rows).
  void add(const double* u, const double* v, double* out, Index r0, Index r1) const { kernel_(*this, u, v, out, r0, r1); }
  // The band form is used (else the compressed rows).
  bool banded() const { return banded_; }
  // How far from its row a row's entries lie: max |i - j| over the stored entries of K and C.
  Index reach() const { return reach_; }

 private:
  using Kernel = void (*)(const LinearProduct&, const double*, const double*, double*, Index, Index);
  static constexpr int kNone = -1;     // no matrix
  static constexpr int kGeneral = -2;  // not a complete band of half-width <= 2
  static constexpr int kMaxBand = 2;

  static Index reach_of(const RowMatrix& A) {
    Index r = 0;
    for (Index i = 0; i < A.outerSize(); ++i)
      for (RowMatrix::InnerIterator it(A, i); it; ++it) r = std::max<Index>(r, std::abs(it.col() - i));
    return r;
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
    // The interior rows: every column of the band inside the matrix, the widths known here.
    for (Index i = head; i < tail; ++i) {
      double s = out[i];
      if constexpr (BK >= 0)
        for (int o = -BK; o <= BK; ++o) s += kb[(o + BK) * n + i] * u[i + o];
      if constexpr (BC >= 0)
        for (int o = -BC; o <= BC; ++o) s += cb[(o + BC) * n + i] * v[i + o];
      out[i] = s;
    }
    for (Index i = tail; i < r1; ++i)
      out[i] = band_row_checked<BC>(band_row_checked<BK>(out[i], kb, u, i, n), cb, v, i, n);
    (void)kb, (void)cb, (void)u, (void)v;
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
  Kernel kernel_ = &add_rows;
  bool banded_ = false;
};

}  // namespace nvib
