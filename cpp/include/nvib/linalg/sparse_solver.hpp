// The sparse linear solver of the Newton component, for models whose force
// gives its tangent entry by entry (effects, laws on measures).
//
// Set-up, once per stepper: the pattern of S = cM M + cC C_t + cK K_t is the
// union of the mass, the linear K and C and the entries of the nonlinear
// tangent; each contribution gets its position in S's values, so that every
// factorisation only adds numbers into place (no search, no allocation).
// The symbolic analysis (with a fill-reducing ordering: AMD for LDL^T, COLAMD
// for LU) is done there too. Then:
//   symmetric S (symmetric K and C: every effect's g g^T is): sparse LDL^T,
//     falling back to sparse LU for a matrix LDL^T without pivoting cannot take;
//   otherwise sparse LU.
// The factorisation is reused as long as the Newton component keeps S (modified
// Newton, a linear model). LDL^T refactorises and solves without allocating (see
// sparse_cholesky.hpp; only its scratch vectors beyond 128 kB go to the heap, Eigen's
// limit for the stack); sparse LU allocates in every factorisation and solve.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/SparseCholesky>
#include <Eigen/SparseLU>

#include "../core/interrupt.hpp"
#include "../core/types.hpp"
#include "iteration_matrix.hpp"
#include "sparse_cholesky.hpp"

namespace nvib {

class SparseLinearSolver {
 public:
  const char* name() const { return lu_now_ ? "sparse LU" : "sparse LDLT"; }
  Index nonzeros() const { return static_cast<Index>(S_.nonZeros()); }
  bool ready() const { return ready_; }

  template <class ModelT>
  void setup(const ModelT& model) {
    const Index n = model.size();
    velocity_ = model.uses_velocity();
    kent_.clear();
    cent_.clear();
    model.tangent_entries(kent_, cent_);
    if (!velocity_) cent_.clear();
    kvals_.assign(kent_.size(), 0.0);
    cvals_.assign(cent_.size(), 0.0);
    // The pattern of S: every contribution, with a zero value (duplicates merge).
    std::vector<Eigen::Triplet<double, int>> all;
    model.mass().for_each_entry([&](Index i, Index j, double) { all.emplace_back(int(i), int(j), 0.0); });
    add_pattern(model.K(), all);
    if (velocity_) add_pattern(model.C(), all);
    for (const Entry& e : kent_) all.emplace_back(e.row, e.col, 0.0);
    for (const Entry& e : cent_) all.emplace_back(e.row, e.col, 0.0);
    S_.resize(n, n);
    S_.setFromTriplets(all.begin(), all.end());
    S_.makeCompressed();
    all.clear();
    all.shrink_to_fit();
    // Where each contribution goes.
    posM_.clear();
    mvals_.clear();
    model.mass().for_each_entry([&](Index i, Index j, double m) {
      posM_.push_back(position(S_, int(i), int(j)));
      mvals_.push_back(m);
    });
    positions_of(model.K(), S_, posK_);
    if (velocity_) positions_of(model.C(), S_, posC_);
    positions_of(kent_, S_, posNK_);
    positions_of(cent_, S_, posNC_);
    // C_t alone, for the incremental format's C_t (v1 - v_n).
    if (velocity_) {
      Ct_.resize(n, n);
      for (const Entry& e : cent_) all.emplace_back(e.row, e.col, 0.0);
      add_pattern(model.C(), all);
      Ct_.setFromTriplets(all.begin(), all.end());
      Ct_.makeCompressed();
      positions_of(model.C(), Ct_, posCtC_);
      positions_of(cent_, Ct_, posCtN_);
    }
    poll_interrupt();
    symmetric_ = is_symmetric(model.K()) && (!velocity_ || is_symmetric(model.C()));
    lu_now_ = !symmetric_;
    if (symmetric_)
      ldlt_.analyze(S_);
    else
      lu_.analyzePattern(S_);
    lu_analyzed_ = !symmetric_;
    work_.setZero(n);
    kdiag_.setZero(n);
    ready_ = true;
  }

  template <class ModelT>
  bool factorize(ModelT& model, const IterationMatrix& im, Stats& st) {
    if (!ready_) setup(model);
    model.tangent_values(*im.u, *im.v, im.t, kvals_.data(), cvals_.data(), st);
    for (double x : kvals_)
      if (!std::isfinite(x)) return false;
    for (double x : cvals_)
      if (!std::isfinite(x)) return false;
    double* s = S_.valuePtr();
    std::fill_n(s, S_.nonZeros(), 0.0);
    for (size_t k = 0; k < posM_.size(); ++k) s[posM_[k]] += im.cM * mvals_[k];
    add_values(model.K(), posK_, im.cK, s);
    for (size_t k = 0; k < posNK_.size(); ++k) s[posNK_[k]] += im.cK * kvals_[k];
    if (velocity_) {
      add_values(model.C(), posC_, im.cC, s);
      for (size_t k = 0; k < posNC_.size(); ++k) s[posNC_[k]] += im.cC * cvals_[k];
      double* c = Ct_.valuePtr();
      std::fill_n(c, Ct_.nonZeros(), 0.0);
      add_values(model.C(), posCtC_, 1.0, c);
      for (size_t k = 0; k < posCtN_.size(); ++k) c[posCtN_[k]] += cvals_[k];
    }
    K_ = &model.K();
    lu_now_ = !symmetric_;
    if (symmetric_) {
      ldlt_.factorize_values(S_);
      if (ldlt_.info() == Eigen::Success && regular(ldlt_.pivots())) {
        st.linear_solver = name();
        return true;
      }
      lu_now_ = true;  // a zero or tiny pivot without pivoting: LU with pivoting may still do
    }
    if (!lu_analyzed_) {
      lu_.analyzePattern(S_);
      lu_analyzed_ = true;
    }
    lu_.factorize(S_);
    st.linear_solver = name();
    return lu_.info() == Eigen::Success;
  }

  void solve_in_place(Vector& x) const {
    if (lu_now_) {
      work_ = x;
      x = lu_.solve(work_);
    } else {
      ldlt_.solve_in_place(x.data(), work_);
    }
  }
  void multiply_C(const Vector& x, Vector& out) const {
    if (velocity_)
      out.noalias() = Ct_ * x;
    else
      out.setZero();
  }
  // The diagonal of K_t at the last factorisation.
  const Vector& tangent_diagonal() {
    kdiag_.setZero();
    if (K_ != nullptr)
      for (Index j = 0; j < K_->outerSize(); ++j)
        for (SparseMatrix::InnerIterator it(*K_, j); it; ++it)
          if (it.row() == j) kdiag_[j] += it.value();
    for (size_t k = 0; k < kent_.size(); ++k)
      if (kent_[k].row == kent_[k].col) kdiag_[kent_[k].row] += kvals_[k];
    return kdiag_;
  }
  Index first_nonfinite_tangent_row() const {
    for (size_t k = 0; k < kvals_.size(); ++k)
      if (!std::isfinite(kvals_[k])) return kent_[k].row;
    for (size_t k = 0; k < cvals_.size(); ++k)
      if (!std::isfinite(cvals_[k])) return cent_[k].row;
    return -1;
  }

 private:
  static void add_pattern(const SparseMatrix& A, std::vector<Eigen::Triplet<double, int>>& out) {
    for (Index j = 0; j < A.outerSize(); ++j)
      for (SparseMatrix::InnerIterator it(A, j); it; ++it) out.emplace_back(it.row(), int(j), 0.0);
  }
  // The index in A's values of entry (i, j), which the pattern holds.
  static int position(const SparseMatrix& A, int i, int j) {
    const int* rows = A.innerIndexPtr();
    const int *b = rows + A.outerIndexPtr()[j], *e = rows + A.outerIndexPtr()[j + 1];
    return static_cast<int>(std::lower_bound(b, e, i) - rows);
  }
  static void positions_of(const SparseMatrix& A, const SparseMatrix& S, std::vector<int>& pos) {
    pos.clear();
    for (Index j = 0; j < A.outerSize(); ++j)
      for (SparseMatrix::InnerIterator it(A, j); it; ++it) pos.push_back(position(S, it.row(), int(j)));
  }
  static void positions_of(const std::vector<Entry>& entries, const SparseMatrix& S, std::vector<int>& pos) {
    pos.clear();
    pos.reserve(entries.size());
    for (const Entry& e : entries) pos.push_back(position(S, e.row, e.col));
  }
  // S[pos[k]] += c A.values[k] (A's values in its storage order, which positions_of followed).
  static void add_values(const SparseMatrix& A, const std::vector<int>& pos, double c, double* s) {
    const double* a = A.valuePtr();
    for (size_t k = 0; k < pos.size(); ++k) s[pos[k]] += c * a[k];
  }
  static bool is_symmetric(const SparseMatrix& A) {
    if (A.nonZeros() == 0) return true;
    const SparseMatrix D = SparseMatrix(A.transpose()) - A;
    double dmax = 0.0, amax = 0.0;
    for (Index k = 0; k < D.nonZeros(); ++k) dmax = std::max(dmax, std::abs(D.valuePtr()[k]));
    for (Index k = 0; k < A.nonZeros(); ++k) amax = std::max(amax, std::abs(A.valuePtr()[k]));
    return dmax <= 1e-14 * amax;
  }
  // The pivots of LDL^T: finite and none below 1e-14 of the largest (as the dense LU's test).
  static bool regular(const Vector& d) {
    double lo = std::numeric_limits<double>::infinity(), hi = 0.0;
    for (Index i = 0; i < d.size(); ++i) {
      const double a = std::abs(d[i]);
      if (!std::isfinite(a)) return false;
      lo = std::min(lo, a);
      hi = std::max(hi, a);
    }
    return d.size() > 0 && lo > 1e-14 * hi;
  }

  bool ready_ = false, velocity_ = false, symmetric_ = true, lu_now_ = false, lu_analyzed_ = false;
  SparseMatrix S_, Ct_;
  const SparseMatrix* K_ = nullptr;
  std::vector<Entry> kent_, cent_;
  std::vector<double> kvals_, cvals_, mvals_;
  std::vector<int> posM_, posK_, posC_, posNK_, posNC_, posCtC_, posCtN_;
  OrderedCholesky<true> ldlt_;
  Eigen::SparseLU<SparseMatrix, Eigen::COLAMDOrdering<int>> lu_;
  mutable Vector work_;
  Vector kdiag_;
};

}  // namespace nvib
